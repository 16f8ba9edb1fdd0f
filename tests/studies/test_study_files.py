"""Batch and suite files are validated by the same mechanism as scenario files (core.config.build):
one ScenarioError naming the file, the dotted key and what was expected."""
import pathlib

import pytest

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies import batch, suite

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCN = (ROOT / "scenarios" / "crash_straight.toml").as_posix()

BATCH_CASES = [
    ("", "runs", "expected a value"),
    ("workers = 1\n", "runs", "required"),
    ("runs = []\n", "runs", "non-empty list"),
    (f'colour = 1\n[[runs]]\nscenario = "{SCN}"\nseeds = 1\n', "colour", "known keys"),
    (f'[[runs]]\nscenario = "{SCN}"\nseeds = 1\nsped = 2\n', "runs[0].sped", "known keys"),
    ('[[runs]]\nseeds = 1\n', "runs[0].scenario", "required"),
    ('[[runs]]\nscenario = ""\nseeds = 1\n', "runs[0].scenario", "non-empty string"),
    (f'[[runs]]\nscenario = "{SCN}"\n', "runs[0].seeds", "required"),
    (f'[[runs]]\nscenario = "{SCN}"\nseeds = "x-y"\n', "runs[0].seeds", "seeds like"),
    (f'[[runs]]\nscenario = "{SCN}"\nseeds = 1\nset = "a=1"\n', "runs[0].set", "a list of"),
    (f'[[runs]]\nscenario = "{SCN}"\nseeds = 1\ncontrollers = [1]\n', "runs[0].controllers[0]", "a string"),
    (f'[[runs]]\nscenario = "{SCN}"\nseeds = 1\ngrid = {{"ego.x" = 3}}\n', "runs[0].grid.ego.x", "non-empty list"),
    (f'workers = 0\n[[runs]]\nscenario = "{SCN}"\nseeds = 1\n', "workers", "positive integer"),
    (f'timeout_s = -1\n[[runs]]\nscenario = "{SCN}"\nseeds = 1\n', "timeout_s", "positive number"),
    (f'ledger = 3\n[[runs]]\nscenario = "{SCN}"\nseeds = 1\n', "ledger", "a string"),
]



ENTRY = f'[[entry]]\nname = "a"\nscenario = "{SCN}"\nseeds = 1\ncriteria = ["collisions == 0"]\n'
SUITE_CASES = [
    ("", "entry", "required"),
    ("[defaults]\nseeds = 1\n", "entry", "required"),
    ("[defaults]\nsped = 1\n" + ENTRY, "defaults.sped", "known keys"),
    (ENTRY + ENTRY, "entry[1].name", "a name not used by another entry"),
    (ENTRY.replace('name = "a"', 'name = ""'), "entry[0].name", "non-empty string"),
    (ENTRY.replace('criteria = ["collisions == 0"]', "criteria = []"), "entry[0].criteria", "non-empty list"),
    (ENTRY.replace('["collisions == 0"]', '["collisions ~ 0"]'), "entry[0].criteria[0]", "a criterion like"),
    (ENTRY.replace("seeds = 1\n", ""), "entry[0].seeds", "here or in [defaults]"),
    (ENTRY + "colour = 2\n", "entry[0].colour", "known keys"),
    (ENTRY.replace("seeds = 1", "seeds = true"), "entry[0].seeds", "a string or an integer"),
]


CASES = [(batch.load_batch_file, *c) for c in BATCH_CASES] + [(suite.load, *c) for c in SUITE_CASES]


@pytest.mark.parametrize("load,text,key,expected", CASES)
def test_bad_file_names_file_key_and_expectation(tmp_path, load, text, key, expected):
    f = tmp_path / "f.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError) as e:
        load(f)
    assert e.value.file == str(f) and e.value.key == key and expected in str(e.value)
    assert "\n" not in str(e.value)


def test_suite_defaults_apply_to_entries(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[defaults]\nseeds = "1-2"\nset = ["sim.duration_s=5"]\n'
                 + ENTRY.replace("seeds = 1\n", 'set = ["sim.step_s=0.1"]\n'))
    (e,) = suite.load(f, extra_sets=("sim.seed=3",))
    assert e.seeds == (1, 2) and e.overrides == ("sim.duration_s=5", "sim.step_s=0.1", "sim.seed=3")
