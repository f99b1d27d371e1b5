"""Which obstacle updates were lost, from the publication sequence numbers DDS gives them.

Every DDS writer numbers its samples 1, 2, 3, ... and rclpy passes the number to a
subscription callback that takes message info (`publication_sequence_number`). A reader
that sees every sample of a writer sees consecutive numbers; a sample dropped on the way
(by the writer's history when the reader lagged, or by the reader's queue when it was
full) leaves a jump. rclpy 7.1 does not pass the writer's GID, so the streams of several
publishers are told apart by their numbers alone: a number continues the stream that
expects it, a 1 starts a new stream (a new publisher), and any other number is a gap.

Limits, which the README repeats: with several publishers, a jump in one stream that
lands on the number another stream expects is taken for that stream, and seen as a gap
only at that stream's next update; a middleware that does not number its samples (the
number is None or 0) allows no detection at all.
"""

from __future__ import annotations

from dataclasses import dataclass

STREAMS_KEPT = 64  # publishers remembered (the least recently heard from are forgotten)


@dataclass(frozen=True)
class Gap:
    """Updates lost before update `number`; `expected` is the one its stream waited for."""

    number: int
    expected: int | None = None

    def describe(self) -> str:
        """Say which updates were not received."""
        if self.expected is not None and self.expected < self.number - 1:
            return f'updates {self.expected} to {self.number - 1} were not received'
        if self.expected is not None and self.expected == self.number - 1:
            return f'update {self.expected} was not received'
        return f'update {self.number} arrived without update {self.number - 1} before it'


class UpdateStreams:
    """The next publication sequence number each publisher's stream expects."""

    def __init__(self, most: int = STREAMS_KEPT):
        self.most = most
        self._expected: list[int] = []  # each stream's next number, least recent first
        self.numbered = True  # False once an update came without a number

    def receive(self, number: int | None) -> Gap | None:
        """Take the publication sequence number of the next update received; None: no gap.

        A number that no stream expects is a gap, unless it is 1 (a new publisher's
        first update); its stream goes on from it either way.
        """
        if not number:
            self.numbered = False
            return None
        gap = None
        if number in self._expected:
            self._expected.remove(number)
        elif number != 1:
            gap = Gap(number, self._expected[0] if len(self._expected) == 1 else None)
        self._expected.append(number + 1)
        del self._expected[:-self.most]
        return gap
