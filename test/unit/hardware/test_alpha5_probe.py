"""Asking an Alpha 5 device for its identity and limits: a lost answer is asked for again."""

from __future__ import annotations

from uvms_hardware.alpha5_checks import check_device
from uvms_hardware.alpha5_probe import probe_device
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import PacketId
from uvms_twins.alpha5_twin import Alpha5Twin

from uvms_hardware import reach_protocol as rp


class LossyLink:
    """A link to the twin that loses the first ``lose`` answers to a LIMITS request."""

    def __init__(self, twin: Alpha5Twin, lose: int) -> None:
        self.twin = twin
        self.lose = lose
        self.sent: list[bytes] = []
        self._inbox = b''

    def send(self, data: bytes) -> None:  # noqa: D102 (transport.Link's)
        self.sent.append(data)
        reply = b''.join(self.twin.handle(p) for p in rp.FrameSplitter().feed(data))
        asks_limits = any(p.packet_id == PacketId.POSITION_LIMITS
                          for p in rp.FrameSplitter().feed(reply))
        if asks_limits and self.lose > 0:
            self.lose -= 1
            return
        self._inbox += reply

    def read(self) -> bytes:  # noqa: D102
        data, self._inbox = self._inbox, b''
        return data

    def wait(self, timeout_s: float) -> bool:  # noqa: D102
        return bool(self._inbox)

    def close(self) -> None:  # noqa: D102
        pass


def test_a_lost_limits_answer_is_asked_again_and_the_device_passes() -> None:
    """One LIMITS answer lost (a datagram, a late twin): the second try has them all."""
    arm = load_alpha5('bluerov2_alpha5')
    drive = arm.drives[0]
    link = LossyLink(Alpha5Twin(arm, port=0), lose=1)
    answers, mode = probe_device(link, rp.FrameSplitter(), drive, timeout_s=0.01)
    assert check_device(drive, answers, 0.01) == []
    assert mode is not None
    assert len(link.sent) == 3  # identity, limits lost, limits again


def test_a_device_that_never_answers_its_limits_is_named_after_every_try() -> None:
    """Lost on every try: the check names each missing limit, after ``tries`` requests."""
    arm = load_alpha5('bluerov2_alpha5')
    drive = arm.drives[0]
    link = LossyLink(Alpha5Twin(arm, port=0), lose=10)
    answers, _ = probe_device(link, rp.FrameSplitter(), drive, timeout_s=0.01, tries=3)
    errors = check_device(drive, answers, 0.01)
    assert any('no POSITION_LIMITS answer' in e for e in errors)
    assert len(link.sent) == 4  # identity, then limits three times
