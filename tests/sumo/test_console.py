"""SUMO's console output during a run: native writes to descriptor 2 go to a file, the log's
warnings and errors are counted, and what the log does not hold is handed back."""
import os

from sumo_avoid.sumo.console import leftover, summary_line, sumo_console_to


def test_native_stderr_goes_to_the_file_and_the_log_is_counted(tmp_path):
    native, log = tmp_path / "stderr.txt", tmp_path / "sumo.log"
    with sumo_console_to(native):
        os.write(2, b"Warning: Vehicle 'a' performs emergency braking\nsomething else\n")
    assert native.read_text().startswith("Warning: Vehicle 'a'")
    log.write_text("Loading done.\nWarning: Vehicle 'a' performs emergency braking\nWarning: two\n"
                   "Error: three\nA Warning: in the middle is no warning\n")
    assert summary_line(log) == "sumo.log: 2 warnings, 1 error"
    assert leftover(native, log) == ["something else"]
    log.write_text("Warning: one\n")
    assert summary_line(log) == "sumo.log: 1 warning"
    assert summary_line(tmp_path / "none.log") == "sumo.log: 0 warnings"
