"""docs/scenario_format.md is generated from the config dataclasses and must stay in sync."""
from conftest import ROOT

from sumo_avoid.scenario.key_reference import format_reference


def test_scenario_format_doc_is_current():
    doc = (ROOT / "docs" / "scenario_format.md").read_text()
    assert doc.strip() == format_reference().strip(), "run: sumo-avoid keys > docs/scenario_format.md"
