"""The path docs/studies.md gives a newcomer from a 3D twin to a sweep ("Studies in space"),
done as written: `granplate preset 3d-ptfe-r05 > my.toml`, its [layout] replaced by the
documented hexagonal table, the documented study file beside it. Truth: the documented
layout is the twin's packing (granules and the placed slab with its rigid layers equal),
and every design of the study validates, with the columns and intruders it names."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import granplate as gp
from granplate.cli import main
from granplate.setup.geometry import resolve
from granplate.setup.presets import preset
from granplate.study.spec import load_study

DOC = (Path(__file__).resolve().parent.parent / "docs" / "studies.md").read_text()
SECTION = DOC.split("## Studies in space: from a 3D twin to a sweep", 1)[1].split("\n## ", 1)[0]


def blocks(kind: str) -> list[str]:
    """The section's fenced code blocks of one language, in order."""
    return re.findall(rf"```{kind}\n(.*?)```", SECTION, flags=re.S)


@pytest.fixture
def study_dir(tmp_path, capsys):
    """my.toml written by the CLI as the section says, its [layout] replaced by the
    documented table, and the documented study.toml beside it."""
    assert blocks("bash")[0].strip() == "granplate preset 3d-ptfe-r05 > my.toml"
    assert main(["preset", "3d-ptfe-r05"]) == 0
    text = capsys.readouterr().out
    start, end = text.index("[layout]"), text.index("[plate]")
    layout, study = blocks("toml")
    (tmp_path / "my.toml").write_text(text[:start] + layout + "\n" + text[end:])
    (tmp_path / "study.toml").write_text(study)
    return tmp_path


def test_documented_layout_is_the_twins_packing(study_dir):
    """The hexagonal table with intruder_columns = "even" builds the twin's granules, walls
    and placed slab with the same rigid layers; the walls at the same offsets to round-off."""
    mine, twin = resolve(gp.load(study_dir / "my.toml")), resolve(preset("3d-ptfe-r05"))
    key = lambda g: (g.x, g.y, g.z, g.radius, g.material)  # noqa: E731
    assert [key(g) for g in mine.granules] == [key(g) for g in twin.granules]
    assert mine.plate == twin.plate
    assert [w.normal for w in mine.walls] == [w.normal for w in twin.walls]
    assert [w.offset for w in mine.walls] == pytest.approx([w.offset for w in twin.walls], rel=1e-14, abs=1e-15)


def test_every_documented_design_validates_with_its_columns(study_dir):
    """The study is intruder material x columns 3, 5, 7; each design validates, holds
    (columns + 1) // 2 heavy and columns // 2 intruder columns of 5 and 4 granules, and its
    slab's rigid layers sit at the granules of the last column."""
    from granplate.setup.validate import validated

    study = load_study(study_dir / "study.toml")
    assert study.names == ("layout.intruder_material", "layout.columns")
    assert len(study.designs) == 6
    for i, (material, columns) in enumerate(study.designs):
        s = resolve(validated(study.scenario(i)))
        light = [g for g in s.granules if g.radius < 0.01]
        assert len(s.granules) == 5 * ((columns + 1) // 2) + 4 * (columns // 2)
        assert len(light) == 4 * (columns // 2) and {g.material for g in light} == {material}
        last = max(g.x for g in s.granules)
        assert len(s.plate.rigid_patches) == sum(1 for g in s.granules if g.x == last) == 5
