"""cantools loads the DBC files and decodes the fixed fields of every frame type the encoder
produces (board 0, the DBC's IDs)."""

from __future__ import annotations

import cantools
import pytest
from protocol_examples import ACK, COMMAND, EVENTS, MARKER, STATUS

from protocols import DBC_FD_PATH, DBC_PATH, CanEncoder

CLASSES = {1: "SKIN_COMMAND", 2: "SKIN_ACK", 3: "SKIN_SYNC", 4: "SKIN_STATUS",
           5: "SKIN_MARKER", 6: "SKIN_EVENTS"}


@pytest.mark.parametrize("fd", [False, True])
def test_dbc_decodes_every_frame_type(fd: bool) -> None:
    db = cantools.database.load_file(str(DBC_FD_PATH if fd else DBC_PATH))
    assert {m.name for m in db.messages} == set(CLASSES.values())
    assert all(m.is_fd == fd for m in db.messages)
    enc = CanEncoder(board_id=0, fd=fd)
    frames = (enc.events(EVENTS, 1000) + enc.status(STATUS) + enc.marker(MARKER)
              + enc.ack(ACK))
    frames += CanEncoder(board_id=0, fd=fd).command(COMMAND)
    seen = set()
    statuses: dict[str, int] = {}
    for seq, f in enumerate(frames[:-1]):
        msg = db.get_message_by_frame_id(f.arbitration_id)
        seen.add(msg.name)
        d = msg.decode(f.data, decode_choices=False, allow_truncated=True)
        assert d["Seq"] == seq % (256 if fd else 16)
        if msg.name == "SKIN_SYNC":
            assert d["StepUs"] == 100 and d["BaseSteps"] == 0 and d["Epoch"] == 0
        elif msg.name == "SKIN_EVENTS":
            assert d["Offset"] == 0 and d["Epoch"] == 0
            n = d["Count"] if fd else 4
            assert [d[f"Ev{i}Addr"] for i in range(n)] == EVENTS["addr"].tolist()
            assert [d[f"Ev{i}Delta"] for i in range(n)] == [0, 0, 3, 6]
        elif msg.name == "SKIN_STATUS":
            statuses.update({k: int(v) for k, v in d.items()})
        elif msg.name == "SKIN_MARKER":
            assert d["TimeUs"] == MARKER.t_us and d["StimulusId"] == MARKER.stimulus_id
            assert d["Phase"] == MARKER.phase
        elif msg.name == "SKIN_ACK":
            assert (d["Token"], d["Opcode"], d["Ok"], d["Reason"]) == (
                ACK.token, ACK.opcode, ACK.ok, ACK.reason)
    cmd = db.get_message_by_frame_id(frames[-1].arbitration_id).decode(
        frames[-1].data, decode_choices=False)
    seen.add("SKIN_COMMAND")
    assert (cmd["Token"], cmd["Opcode"], cmd["Seq"]) == (COMMAND.token, COMMAND.opcode, 0)
    assert seen == set(CLASSES.values())
    assert statuses["TimeUs"] == STATUS.t_us and statuses["Running"] == 1
    for field, name in (("events_generated", "EventsGenerated"), ("events_sent", "EventsSent"),
                        ("events_dropped", "EventsDropped"), ("late_ticks", "LateTicks"),
                        ("events_queued", "EventsQueued"),
                        ("dropped_fifo_full", "DroppedFifoFull"),
                        ("dropped_stopped", "DroppedStopped")):
        assert statuses[name] == getattr(STATUS, field)
    assert statuses["LinkEvents"] == len(EVENTS)
