"""The Compare tab's table (app/explorer/compare_panel.comparison_table): with one pin its "change" column
gives current minus pinned for every numeric row, TI_1 and TI_2 included, except where a value is only a
lower bound (a difference of lower bounds says nothing of the indices)."""

from __future__ import annotations

from types import SimpleNamespace

from paraspace.app.explorer.compare_panel import comparison_table
from paraspace.kinematics.design import Design


def _bundle(design: Design) -> SimpleNamespace:
    # only the design: the table leaves out the rows a bundle cannot answer
    return SimpleNamespace(result=SimpleNamespace(design=design))


def _row(table: str, label: str) -> list[str]:
    line = next(x for x in table.splitlines() if x.startswith(f"| {label}"))
    return [c.strip() for c in line.strip("|").split("|")]


def test_one_pin_gives_the_change_of_each_index_unless_a_lower_bound():
    pin, cur = _bundle(Design(a=50.0)), _bundle(Design(a=70.0))
    table = comparison_table([pin], cur, [(29400.0, 13580.0, True, False), (32040.0, 9062.0, True, False)])
    assert _row(table, "a · platform radius")[-1] == "+20.0 (+40 %)"
    ti1, ti2 = _row(table, "TI₁"), _row(table, "TI₂")
    assert ti1[1:] == ["≥ 29,400", "≥ 32,040", "(a lower bound)"]
    # 9,062 - 13,580 = -4,518, -33.3 % of the pin's
    assert ti2[1:3] == ["13,580", "9,062"] and ti2[3].startswith("-4,5") and ti2[3].endswith("(-33 %)")
    table = comparison_table([pin], cur, [(29400.0, 13580.0, False, False), (29400.0, 13580.0, False, True)])
    assert _row(table, "TI₁")[3] == "0 (+0 %)" and _row(table, "TI₂")[3] == "(a lower bound)"


def test_several_pins_have_no_change_column():
    table = comparison_table([_bundle(Design(a=50.0)), _bundle(Design(a=60.0))], _bundle(Design(a=70.0)),
                             [(1.0, 2.0, False, False)] * 3)
    assert len(_row(table, "TI₂")) == 4 and "change" not in table.splitlines()[0]
