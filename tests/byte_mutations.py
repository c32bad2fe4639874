"""Byte mutations of a file for the importers' fuzz tests: the file cut short, some of its bytes overwritten, and
the import either loading or refusing in one line."""

from collections.abc import Callable
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vinadv.errors import InputError

#: hypothesis strategies for `mutated`'s arguments: `@given(**MUTATIONS)`
MUTATIONS = {
    "cut": st.floats(0, 1),
    "flips": st.lists(st.tuples(st.floats(0, 1), st.integers(0, 255)), max_size=4),
}


def mutated(data: bytes, cut: float, flips: list[tuple[float, int]]) -> bytes:
    """`data` cut at the share `cut` of its length where `cut` < 0.5 (else whole), then each `(where, value)` of
    `flips` writing `value` at the share `where` of what is left."""
    out = bytearray(data[: max(1, int(cut * len(data)))] if cut < 0.5 else data)
    for where, value in flips:
        out[min(len(out) - 1, int(where * len(out)))] = value
    return bytes(out)


def refused_mutations(target: Path, load: Callable[[], object], examples: int = 30) -> list[float]:
    """Write `examples` mutations of `target`'s bytes to it (fixed examples), calling `load()` after each: it loads
    or raises an InputError of one line (anything else fails the test). The `cut` of each mutation refused."""
    data, refused = target.read_bytes(), []

    @settings(max_examples=examples, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
    @given(**MUTATIONS)
    def check(cut, flips):
        target.write_bytes(mutated(data, cut, flips))
        try:
            load()
        except InputError as exc:
            assert str(exc) and "\n" not in str(exc), repr(exc)
            refused.append(cut)

    check()
    return refused
