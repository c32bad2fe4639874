"""Byte mutations of a file for the importers' fuzz tests: the file cut short, some of its bytes overwritten."""

from hypothesis import strategies as st

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
