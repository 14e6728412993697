"""python-can's own configuration and extra bus arguments reach ``can.Bus``.

A CAN link given no interface takes the one python-can's configuration names
(``CAN_INTERFACE``, ``~/.canrc``), as ``can.Bus(channel=...)`` would, and ``--bus-kwargs``
(``bus_kwargs=`` in a ``can:`` URL) are passed to ``can.Bus``. Played on python-can's
``virtual`` interface: no vcan needed.
"""

from __future__ import annotations

import uuid
from pathlib import Path

import pytest

from skinhil.errors import TransportError
from skinhil.transports import open_link
from skinhil.transports.can import (
    DEFAULT_CAN_INTERFACE,
    CanTransport,
    parse_bus_kwargs,
)


@pytest.fixture
def no_can_config(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """No python-can configuration from the environment or the user's files: HOME is a new
    folder (returned), the CAN_* variables unset."""
    for name in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    return tmp_path


def _channel() -> str:
    return f"skinhil-{uuid.uuid4().hex[:8]}"


def _frame(n: int) -> object:
    from protocols import CanFrame

    return CanFrame(arbitration_id=0x100 + n, data=bytes([n] * 8), is_fd=False)


def _exchange(tx: CanTransport, rx: CanTransport) -> list[object]:
    tx.send([_frame(1)], timeout=1.0)
    return rx.recv(timeout=1.0)


def test_interface_from_environment(no_can_config: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    chan = _channel()
    with CanTransport(chan) as tx, open_link(f"can:{chan}", "host") as rx:
        assert tx.interface == "virtual" and rx.interface == "virtual"  # type: ignore[attr-defined]
        assert [f.arbitration_id for f in _exchange(tx, rx)] == [0x101]  # type: ignore[arg-type, attr-defined]


def test_interface_and_bitrate_from_canrc(no_can_config: Path) -> None:
    (no_can_config / ".canrc").write_text("[default]\ninterface = virtual\nbitrate = 250000\n")
    chan = _channel()
    with CanTransport(chan) as bus:
        assert (bus.interface, bus.bitrate) == ("virtual", 250_000)
        assert "interface=virtual" in bus.url and "bitrate=250000" in bus.url


def test_given_interface_wins_and_default_without_config(no_can_config: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CAN_INTERFACE", "no_such_interface_here")
    with CanTransport(_channel(), "virtual") as bus:  # given: the environment is not read
        assert bus.interface == "virtual"
    with pytest.raises(TransportError, match="CAN_INTERFACE"):
        CanTransport(_channel())
    monkeypatch.delenv("CAN_INTERFACE")
    from skinhil.transports.can import configured_bus

    assert "interface" not in configured_bus("can0")  # so the link takes its default
    assert DEFAULT_CAN_INTERFACE == "socketcan"


def test_bus_kwargs_reach_can_bus(no_can_config: Path) -> None:
    chan = _channel()
    with CanTransport(chan, "virtual") as plain:  # the virtual bus drops its own frames...
        plain.send([_frame(2)], timeout=1.0)
        assert plain.recv(timeout=0.2) == []
    url = f"can:{chan}?interface=virtual&bus_kwargs=receive_own_messages=true"
    with open_link(url, "host") as own:  # ...unless receive_own_messages reaches can.Bus
        own.send([_frame(3)], timeout=1.0)
        assert [f.arbitration_id for f in own.recv(timeout=1.0)] == [0x103]  # type: ignore[attr-defined]
        assert "bus_kwargs=" in own.url  # type: ignore[attr-defined]


def test_bus_kwargs_forms() -> None:
    assert parse_bus_kwargs("sjw_abr=8, tseg1_abr=31,app_name=rig,serial=true") == {
        "sjw_abr": 8, "tseg1_abr": 31, "app_name": "rig", "serial": True}
    assert parse_bus_kwargs('{"sjw_abr": 8, "app_name": "rig"}') == {"sjw_abr": 8,
                                                                    "app_name": "rig"}
    assert parse_bus_kwargs("") == {}
    for bad in ("sjw_abr", "bitrate=500000", "[1]", "{bad json"):
        with pytest.raises(ValueError):
            parse_bus_kwargs(bad)


def test_cli_bus_kwargs(no_can_config: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from skinhil.cli.parser import build_parser
    from skinhil.cli.transport_args import open_transport
    from tests.harness.refusals import refusal_failures

    chan = _channel()
    args = build_parser("listen").parse_args(
        ["listen", "--model", "m.npz", "--can", chan, "--interface", "virtual", "--bus-kwargs",
         '{"receive_own_messages": true}'])
    with open_transport(args) as bus:
        bus.send([_frame(4)], timeout=1.0)
        assert [f.arbitration_id for f in bus.recv(timeout=1.0)] == [0x104]

    class Case:
        def __init__(self, name: str, argv: list[str], word: str) -> None:
            self.name, self.argv, self.word = name, argv, word

    assert refusal_failures([
        Case("own key", ["listen", "--can", chan, "--bus-kwargs", "fd=1"], "--fd"),
        Case("not KEY=VALUE", ["listen", "--can", chan, "--bus-kwargs", "x"], "KEY=VALUE"),
        Case("serial", ["listen", "--model", "m.npz", "--port", "/dev/null", "--bus-kwargs",
                             "a=1"], "--can"),
    ], capsys) == []
