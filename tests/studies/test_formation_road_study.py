"""The formation road study's command line: bad flags give one line on stderr, exit 2, nothing written
(its runs are the formation's road case, measured in reports/formation/road)."""
from __future__ import annotations

import pytest

from sumo_avoid.studies.formation_road import main


@pytest.mark.parametrize("argv, key", [(["--seeds", "5-1"], "--seeds"), (["--seeds", "1", "--workers", "0"], "--workers"),
                                       (["--seeds", "1", "--scenario", "nope.toml"], "<file>")])
def test_bad_flags_exit_2_and_write_nothing(tmp_path, capsys, argv, key):
    out = tmp_path / "o"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0]
    assert not out.exists()
