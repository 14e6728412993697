"""``skinhil.toml``: where it is found, what it gives, that the command line wins, and a bad
file refused in one line naming the file and the key."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from skinhil.config import config_paths, load_user_config
from skinhil.errors import ConfigError


@pytest.fixture
def home(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """A user with no configuration: HOME and the working directory are new folders,
    XDG_CONFIG_HOME unset; python-can's CAN_* variables unset. Returns the working
    directory."""
    (tmp_path / "home").mkdir()
    (tmp_path / "work").mkdir()
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("XDG_CONFIG_HOME", raising=False)
    for name in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.chdir(tmp_path / "work")
    return tmp_path / "work"


def _user_file(home: Path) -> Path:
    path = home.parent / "home" / ".config" / "skinhil" / "skinhil.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def _parse(argv: list[str]) -> object:
    """``argv`` parsed as ``skinhil.cli.main`` does, with the configuration found."""
    from skinhil.cli.parser import build_parser
    from skinhil.cli.user_config import apply_config

    config = load_user_config()
    args = build_parser(argv[0], config).parse_args(argv)
    apply_config(args, config)
    return args


def test_search_order_and_xdg(home: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert config_paths() == (home / "skinhil.toml",
                              home.parent / "home" / ".config" / "skinhil" / "skinhil.toml")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home.parent / "xdg"))
    assert config_paths()[1] == home.parent / "xdg" / "skinhil" / "skinhil.toml"
    assert load_user_config().path is None
    user = home.parent / "xdg" / "skinhil" / "skinhil.toml"
    user.parent.mkdir(parents=True)
    user.write_text('port = "/dev/ttyUSB7"\n')
    assert load_user_config().path == user
    (home / "skinhil.toml").write_text('port = "/dev/ttyACM0"\n')  # the working directory's
    found = load_user_config()                                      # wins, not merged
    assert found.path == home / "skinhil.toml" and dict(found.values) == {
        "port": "/dev/ttyACM0"}
    assert f"{home / 'skinhil.toml'} (read)" in found.describe()


def test_defaults_fill_and_command_line_wins(home: Path) -> None:
    _user_file(home).write_text('port = "/dev/ttyUSB7"\nbaud = 115200\nmodel = "dec.npz"\n'
                                'interface = "virtual"\n')
    args = _parse(["listen"])  # neither --port nor --model: both from the file
    assert (args.port, args.baud, args.can) == ("/dev/ttyUSB7", 115200, None)  # type: ignore[attr-defined]
    assert args.model == _user_file(home).parent / "dec.npz"  # type: ignore[attr-defined]
    args = _parse(["listen", "--port", "/dev/pts/9", "--baud", "9600", "--model", "m.npz"])
    assert (args.port, args.baud, str(args.model)) == ("/dev/pts/9", 9600, "m.npz")  # type: ignore[attr-defined]
    args = _parse(["listen", "--can", "vcan1"])  # another link: the serial rate stays out,
    assert (args.port, args.can, args.baud, args.interface) == (  # type: ignore[attr-defined]
        None, "vcan1", None, "virtual")                          # the CAN interface comes in
    args = _parse(["listen", "--link", "udp:127.0.0.1:9000"])  # a URL: nothing added to it
    assert (args.port, args.baud, args.interface) == (None, None, None)  # type: ignore[attr-defined]


def test_can_link_from_file_opens(home: Path) -> None:
    from skinhil.cli.transport_args import open_transport

    (home / "skinhil.toml").write_text(
        'can = "skinhil-cfg"\ninterface = "virtual"\n[bus_kwargs]\nreceive_own_messages = true\n')
    args = _parse(["serve"])
    with open_transport(args) as bus:  # type: ignore[arg-type]
        assert "interface=virtual" in bus.url and "receive_own_messages" in bus.url  # type: ignore[attr-defined]


def test_help_says_which_file(home: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from skinhil.cli import main

    with pytest.raises(SystemExit):
        main(["--help"])
    assert "configuration: none" in capsys.readouterr().out
    (home / "skinhil.toml").write_text('baud = 115200\n')
    with pytest.raises(SystemExit):
        main(["listen", "--help"])
    assert f"  {home / 'skinhil.toml'} (read)\n" in capsys.readouterr().out


@pytest.mark.parametrize(("text", "words"), [
    ('baud = "fast"\n', ("$.baud", "integer")),
    ("baud = 3\n", ("$.baud", "[50, 20000000]")),
    ('prot = "/dev/ttyUSB0"\n', ("'prot'",)),
    ('port = "/dev/x"\ncan = "can0"\n', ("port and can",)),
    ("port = /dev/x\n", ("not TOML",)),
    ("[bus_kwargs]\nbitrate = 5\n", ("bus_kwargs", "--bitrate")),
])
def test_bad_file_one_line(home: Path, capsys: pytest.CaptureFixture[str], text: str,
                           words: tuple[str, ...]) -> None:
    from skinhil.cli import main

    path = home / "skinhil.toml"
    path.write_text(text)
    with pytest.raises(ConfigError):
        load_user_config()
    status = main(["dbc"])  # any command reads it first
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert status == 2 and len(lines) == 1, lines
    assert lines[0].startswith("skinhil: error: ") and str(path) in lines[0]
    for word in words:
        assert word in lines[0], lines[0]


def test_unreadable_file_refused(home: Path) -> None:
    if os.geteuid() == 0:  # root reads any file: a folder in the file's place instead
        (home / "skinhil.toml").mkdir()
        assert load_user_config().path is None  # not a file: not a configuration
        return
    path = home / "skinhil.toml"
    path.write_text("baud = 9600\n")
    path.chmod(0)
    with pytest.raises(ConfigError, match="cannot read"):
        load_user_config()
