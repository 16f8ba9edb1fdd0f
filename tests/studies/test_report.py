"""The HTML report: self-contained (images embedded) and its tables match the ledger."""
import base64
import html.parser
import json
import pathlib

import pandas as pd
import pytest

from sumo_avoid.cli import main
from sumo_avoid.runs import faults
from sumo_avoid.studies import batch, ledger

ROOT = pathlib.Path(__file__).resolve().parents[2]
OVERTAKING = ROOT / "scenarios" / "overtaking.toml"
SHORT = ["sim.duration_s=5", "output.plots=false"]  # no PNGs: the report draws them from trajectories.csv


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    d = tmp_path_factory.mktemp("study")
    specs = batch.expand([OVERTAKING], [1, 2], SHORT, ["apf_sa", "apf"])
    specs += batch.expand([OVERTAKING], [9], SHORT)
    cfg = batch.BatchConfig(tuple(specs), d / "ledger.sqlite", workers=2)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(faults.ENV, "segfault:9")  # test-only fault injection: the seed-9 run crashes
        assert batch.run_batch(cfg, progress=False) == {"total": 5, "skipped": 0, "done": 4, "failed": 1}
    return d


class _Page(html.parser.HTMLParser):
    """Collects <img> sources, external references and the cells of the tables inside div#ID."""

    def __init__(self):
        super().__init__()
        self.imgs, self.refs, self.tables = [], [], {}
        self._div, self._row, self._cell = None, None, None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a.get("src", ""))
        for k in ("href", "src"):
            if k in a and not a[k].startswith("data:"):
                self.refs.append(a[k])
        if tag == "div" and "id" in a:
            self._div = a["id"]
            self.tables[self._div] = []
        elif tag == "tr" and self._div:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell)
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._div].append(self._row)
            self._row = None
        elif tag == "div":
            self._div = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data


def _frame(rows):
    return pd.DataFrame(rows[1:], columns=rows[0])


def _close(cell: str, value) -> bool:
    if value is None or (isinstance(value, float) and value != value):
        return cell == "n/a"
    return abs(float(cell) - float(value)) <= 1e-3 * max(1.0, abs(float(value)))


def test_report_is_self_contained_and_matches_the_ledger(study, tmp_path):
    out = tmp_path / "r.html"
    assert main(["report", str(study / "ledger.sqlite"), "--out", str(out), "--md", str(tmp_path / "s.md"),
                 "--csv", str(tmp_path / "runs.csv")]) == 0
    page = _Page()
    page.feed(out.read_text())
    # nothing to fetch: the only links are to each done run's viewer page, written beside the report
    viewers = [r for r in page.refs if r.startswith("r_viewers/")]
    assert page.refs == viewers and len(viewers) == 4 and all((tmp_path / v).is_file() for v in viewers)
    assert "window.RUN=" in (tmp_path / viewers[0]).read_text()
    assert len(page.imgs) == 2 + 1 + 1  # a trajectory per scenario x controller, box plots, time series
    for src in page.imgs:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"

    df = ledger.read(study / "ledger.sqlite")
    summ = _frame(page.tables["summary"])
    for (scn, ctl), g in df.groupby(["scenario", "controller"]):
        row = summ[(summ["scenario"] == scn) & (summ["controller"] == ctl)].iloc[0]
        d = g[g["status"] == "done"]
        assert (int(row["runs"]), int(row["done"]), int(row["failed"])) == (len(g), len(d), len(g) - len(d))
        if len(d):
            assert _close(row["collisions_total"], d["collisions"].sum())
            assert _close(row["vru_collisions_total"], d["vru_collisions"].sum())
            assert _close(row["collisions_ego_stopped_total"], d["collisions_ego_stopped"].sum())
            assert _close(row["min_gap_m_min"], d["min_gap_m"].min())
            assert _close(row["goal_reached_rate"], d["goal_reached"].mean())
            assert _close(row["mean_speed_mps_mean"], d["mean_speed_mps"].mean())
            assert _close(row["min_ttc_s_min"], d["min_ttc_s"].min())
            assert _close(row["min_ttc2d_s_min"], d["min_ttc2d_s"].min())
            assert _close(row["wrong_way_m_max"], d["wrong_way_m"].max())
            assert _close(row["off_road_m_max"], d["off_road_m"].max())
    runs = _frame(page.tables["runs"]).set_index("key")
    assert len(runs) == len(df) == 5
    for r in df.to_dict(orient="records"):
        shown = runs.loc[r["key"][:16]]
        assert (shown["status"], int(shown["seed"])) == (r["status"], r["seed"])
        for c in ("collisions", "min_gap_m", "phi_wall", "mean_speed_mps", "min_ttc_s", "min_ttc2d_s", "max_drac_mps2",
                  "min_pet_s", "wrong_way_m", "off_road_m", "max_abs_jerk_mps3", "max_lat_accel_mps2"):
            assert _close(shown[c], r[c])
    failed = _frame(page.tables["failed"])
    assert failed["error"].tolist() == ["worker died: SIGSEGV (segmentation fault)"]
    assert "| overtaking | apf_sa | 3 | 2 | 1 |" in (tmp_path / "s.md").read_text()
    assert len(pd.read_csv(tmp_path / "runs.csv")) == 5


def test_report_of_run_folders_and_bad_source(study, tmp_path, capsys):
    out = tmp_path / "r.html"
    assert main(["report", str(study / "runs"), "--out", str(out)]) == 0  # folders with metrics.json
    page = _Page()
    page.feed(out.read_text())
    assert len(_frame(page.tables["runs"])) == 4 and all(s.startswith("data:") for s in page.imgs)
    assert main(["report", str(tmp_path / "nothing"), "--out", str(out)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_report_groups_by_every_dimension_the_batch_varied(tmp_path):
    """A batch over a grid (ego.sensor) and a --set that is the same for every run: the report has a
    row, a box and a trajectory per scenario x controller x sensor (not one row mixing the sensors),
    an ego.sensor column, and nothing for the constant --set."""
    specs = batch.expand([OVERTAKING], [1], SHORT, ["apf_sa"], grid={"ego.sensor": ["truth", "radar"]})
    cfg = batch.BatchConfig(tuple(specs), tmp_path / "ledger.sqlite", workers=2)
    assert batch.run_batch(cfg, progress=False)["done"] == 2
    out = tmp_path / "r.html"
    assert main(["report", str(tmp_path / "ledger.sqlite"), "--out", str(out), "--md", str(tmp_path / "s.md")]) == 0
    page = _Page()
    page.feed(out.read_text())
    summ = _frame(page.tables["summary"])
    assert list(summ.columns[:3]) == ["scenario", "controller", "ego.sensor"]
    assert summ["ego.sensor"].tolist() == ["radar", "truth"] and summ["runs"].tolist() == ["1", "1"]
    assert "sim.duration_s" not in summ.columns and "output.plots" not in summ.columns
    df = ledger.read(tmp_path / "ledger.sqlite")
    for r in df.to_dict(orient="records"):
        sensor = "radar" if 'ego.sensor="radar"' in json.loads(r["overrides"]) else "truth"
        row = summ[summ["ego.sensor"] == sensor].iloc[0]
        assert _close(row["min_gap_m_min"], r["min_gap_m"]) and _close(row["mean_speed_mps_mean"], r["mean_speed_mps"])
    assert "ego.sensor" in _frame(page.tables["runs"]).columns
    assert len(page.imgs) == 2 + 1 + 1  # a trajectory per sensor, box plots, time series
    assert "| overtaking | apf_sa | radar | 1 | 1 | 0 |" in (tmp_path / "s.md").read_text()
