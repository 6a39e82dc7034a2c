"""The kernel's array layouts: every slot family numbered 0 … N−1, each slot commented."""

from __future__ import annotations

import inspect
import re

import pytest

from vfgym.plant import _lanes as LN
from vfgym.plant import _layout as L

FAMILIES = {"P_": "N_PARAMS", "A_": "N_ACC", "R_": "N_ROWS", "S_": "N_STATE"}
SLOT = re.compile(r"^(?P<name>[A-Z][A-Z0-9_]*) = .*$")


def slots(module: object, prefix: str) -> dict[str, int]:
    """The module's int constants named ``prefix``…, by name."""
    return {
        k: v
        for k, v in vars(module).items()
        if k.startswith(prefix) and isinstance(v, int) and not isinstance(v, bool)
    }


def numbering_faults(numbers: dict[str, int], count: int) -> list[str]:
    """What keeps ``numbers`` from being exactly 0 … count−1, each once."""
    faults = []
    seen: dict[int, str] = {}
    for name, i in sorted(numbers.items(), key=lambda kv: kv[1]):
        if i in seen:
            faults.append(f"{name} repeats {seen[i]} = {i}")
        seen[i] = name
    missing = sorted(set(range(count)) - set(seen))
    beyond = sorted(i for i in seen if not 0 <= i < count)
    if missing:
        faults.append(f"no slot numbered {missing}")
    if beyond:
        faults.append(f"slots outside 0..{count - 1}: {beyond}")
    if len(numbers) != count:
        faults.append(f"{len(numbers)} slots, but N = {count}")
    return faults


@pytest.mark.parametrize(("prefix", "count_name"), FAMILIES.items())
def test_each_slot_family_is_numbered_0_to_n_minus_1_once(prefix, count_name):
    numbers = slots(L, prefix)
    assert numbers, prefix
    assert numbering_faults(numbers, getattr(L, count_name)) == []


@pytest.mark.parametrize(
    ("numbers", "count", "fault"),
    [
        ({"X_A": 0, "X_B": 1, "X_C": 2}, 3, None),
        ({"X_A": 0, "X_B": 1, "X_C": 1}, 3, "X_C repeats X_B = 1"),
        ({"X_A": 0, "X_B": 2}, 3, "no slot numbered [1]"),
        ({"X_A": 0, "X_B": 1, "X_C": 3}, 3, "slots outside 0..2: [3]"),
        ({"X_A": 0, "X_B": 1}, 3, "2 slots, but N = 3"),
        ({"X_A": 0, "X_B": 1, "X_C": 2}, 2, "3 slots, but N = 2"),
    ],
)
def test_the_numbering_check_finds_repeats_gaps_and_a_wrong_count(numbers, count, fault):
    faults = numbering_faults(numbers, count)
    assert (fault is None and faults == []) or fault in faults


def test_every_constant_of_the_layout_is_a_slot_or_a_family_count():
    names = {k for k in vars(L) if k.isupper()}
    families = set().union(*(slots(L, p) for p in FAMILIES))
    assert names - families == set(FAMILIES.values())


def test_every_slot_says_what_it_holds():
    """A comment on every slot line (its content and unit, read by people)."""
    bare = [
        line
        for line in inspect.getsource(L).splitlines()
        if (m := SLOT.match(line))
        and m["name"].startswith(tuple(FAMILIES))
        and not re.search(r"#\s*\S", line)
    ]
    assert bare == []


def test_the_lane_block_rows_tile_0_to_n_rows_minus_1():
    """The SIMD block's rows: the parameter row and loop state transposed (N_PARAMS and
    N_STATE rows), then one row per per-tick quantity, without overlap or gap."""
    width = {"Z_PRM": L.N_PARAMS, "Z_ST": L.N_STATE}
    rows: dict[str, int] = {}
    for name, start in slots(LN, "Z_").items():
        for j in range(width.get(name, 1)):
            rows[f"{name}+{j}"] = start + j
    assert numbering_faults(rows, LN.N_ROWS) == []
