"""A stand-in for tqdm in the tests of progress bars: `recorded_bars(monkeypatch)` makes every bar a vinadv function
opens (`from tqdm import tqdm` at the call) a `RecordedBar`, kept in the list it returns."""

from __future__ import annotations

import tqdm


class RecordedBar:
    """What a bar was told: its settings and each update."""

    def __init__(self, made: list, total=None, desc=None, unit=None, initial=0, leave=True):
        self.desc, self.unit, self.initial, self.total, self.leave, self.updates = desc, unit, initial, total, leave, []
        made.append(self)

    def update(self, n):
        self.updates.append(n)

    def close(self):
        pass


def recorded_bars(monkeypatch) -> list[RecordedBar]:
    """The bars opened from now on (in the order opened), tqdm replaced for the test only."""
    made: list[RecordedBar] = []
    monkeypatch.setattr(tqdm, "tqdm", lambda *args, **kwargs: RecordedBar(made, *args, **kwargs))
    return made
