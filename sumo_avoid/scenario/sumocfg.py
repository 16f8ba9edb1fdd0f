"""Scenarios from SUMO configurations: ``sim.sumocfg = "city.sumocfg"`` in a scenario file, or the
``.sumocfg`` itself as the scenario (``sumo-avoid run city.sumocfg --ego ID``).

The configuration's options fill the ``[sim]`` keys the scenario file does not set (TOML keys
override): ``net-file`` -> ``sim.net``, ``route-files`` -> ``sim.routes``, ``additional-files`` ->
``sim.additional``, ``step-length`` -> ``sim.step_s``, ``begin`` -> ``sim.begin_s``, ``end`` ->
``sim.duration_s`` (end - begin), ``seed`` -> ``sim.seed``, ``lateral-resolution`` ->
``sim.lateral_resolution_m``; every other option goes to SUMO as it is, through ``sim.options``
(a ``[sim.options]`` table of the scenario overrides it option by option). Options the plug-in must
own (:func:`owned`) are left out, each with a note in the run's ``sumo.log``. Keys the configuration
does not set either keep the plug-in's defaults (``sim.step_s`` 0.1 s, not SUMO's 1 s: the controllers
are tuned for it; ``sim.duration_s`` 120 s). A bad configuration is one line naming the ``.sumocfg``,
the option and what was expected (:class:`~sumo_avoid.core.config.ScenarioError`).
"""
from __future__ import annotations

import math
import os
import pathlib
from dataclasses import dataclass

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.sumo.options import Option, OptionError, check_value, option, parse_time, read_config, split_files

SUFFIX = ".sumocfg"
# configuration option -> [sim] key
MAPPED = {"net-file": "net", "route-files": "routes", "additional-files": "additional", "step-length": "step_s",
          "begin": "begin_s", "end": "duration_s", "seed": "seed", "lateral-resolution": "lateral_resolution_m"}
_SECTIONS = {
    "output": "the run writes its own outputs into its folder",
    "report": "SUMO's messages go to the run's sumo.log",
    "gui_only": "no GUI: SUMO runs inside the plug-in's process (libsumo)",
    "communication": "no TraCI clients: SUMO runs inside the plug-in's process (libsumo)",
    "traci_server": "no TraCI clients: SUMO runs inside the plug-in's process (libsumo)",
    "configuration": "the plug-in starts SUMO with its own command line",
    "ssm_device": "the plug-in equips the egos with SUMO's SSM device itself",
}


@dataclass(frozen=True)
class SumoConfig:
    """The configuration a scenario was read from."""

    path: pathlib.Path  # absolute
    shown: str  # as the user named it (the scenario itself) or absolute (sim.sumocfg)
    notes: tuple[str, ...]  # for sumo.log: its options the plug-in owns, left out
    keys: tuple[tuple[str, str], ...]  # ("sim.routes", "route-files"): keys taken from its options (or flags)

    def rename(self, err: ScenarioError) -> ScenarioError:
        """``err`` about a value or file the configuration gave, as an error of the configuration's option."""
        option = dict(self.keys).get(err.key.partition("[")[0])
        if option is None:
            return err
        return ScenarioError(self.shown, option, err.expected, err.got, show_got=err.show_got)


def checked(cfg: SumoConfig | None, check, *args):
    """``check(*args)``, its :class:`ScenarioError` about a value the configuration gave renamed to its option."""
    try:
        return check(*args)
    except ScenarioError as e:
        raise (cfg.rename(e) if cfg else e) from None


def is_sumocfg(path) -> bool:
    return pathlib.Path(path).suffix == SUFFIX


def owned(opt: Option) -> str | None:
    """Why the plug-in sets option ``opt`` itself (None: the configuration's value is used)."""
    if opt.name.startswith("collision."):
        return ("the plug-in checks collisions itself and has SUMO report them, never act on them "
                "(collision.action warn, check-junctions, mingap-factor 0)")
    if opt.name.startswith("time-to-teleport"):
        return "vehicles are never teleported (time-to-teleport -1)"
    if opt.name == "random":
        return "runs are seeded (sim.seed)"
    return _SECTIONS.get(opt.section)


def merge(data: dict, base: pathlib.Path, file: str) -> tuple[dict, SumoConfig | None]:
    """(data with ``[sim]`` filled from its ``sim.sumocfg``, the configuration); ``data`` unchanged and
    None when it names no configuration. ``base``: the scenario file's folder."""
    sim = data.get("sim")
    if not isinstance(sim, dict) or "sumocfg" not in sim:
        return data, None
    rel = sim["sumocfg"]
    if not isinstance(rel, str) or not rel:
        raise ScenarioError(file, "sim.sumocfg", "the path of a SUMO configuration (.sumocfg)", rel)
    cfg = (base / rel).resolve()
    if not cfg.is_file():
        raise ScenarioError(file, "sim.sumocfg", "an existing SUMO configuration file", rel)
    shown = file if is_sumocfg(file) else str(cfg)  # the configuration as the user named it
    try:
        opts = read_config(cfg)
    except OptionError as e:
        raise ScenarioError(shown, e.option, e.expected, e.got, show_got=e.show_got) from None
    filled, notes, passed = {}, [], {}
    for name, value in opts.items():
        why = owned(option(name))
        if name in MAPPED:
            filled[MAPPED[name]] = _sim_value(name, value, base, shown)
        elif why is not None:
            notes.append(f"sumo-avoid: option '{name}' of {cfg.name} not used: {why}")
        else:
            passed[name] = value
    end = filled.pop("duration_s", None)
    begin = sim.get("begin_s", filled.get("begin_s", 0.0))
    if end is not None and end >= 0 and "duration_s" not in sim:
        if isinstance(begin, (int, float)) and end <= begin:
            raise ScenarioError(shown, "end", f"an end after the begin ({begin:g} s)", opts["end"])
        filled["duration_s"] = end - begin if isinstance(begin, (int, float)) else end
    options = sim.get("options", {})
    merged = {**passed, **options} if isinstance(options, dict) else options  # a wrong type: build() says so
    if "net" not in sim and "net" not in filled:
        raise ScenarioError(shown, "net-file", "a SUMO network file (option net-file) in the configuration, "
                                                  "or sim.net", show_got=False)
    keys = tuple((f"sim.{MAPPED[n]}", n) for n in opts if n in MAPPED and MAPPED[n] in filled and MAPPED[n] not in sim)
    keys += (("ego.ids", "--ego"),) if is_sumocfg(file) else ()  # the configuration run as it is: its egos are flags
    return {**data, "sim": {**filled, **sim, "options": merged}}, SumoConfig(cfg, shown, tuple(notes), keys)


def _sim_value(name: str, value: str, base: pathlib.Path, cfg: str):
    """The ``[sim]`` value of a mapped configuration option (paths relative to the scenario's folder)."""
    if name in ("net-file", "route-files", "additional-files"):
        files = split_files(value)
        for f in files:
            if not pathlib.Path(f).is_file():
                raise ScenarioError(cfg, name, "existing files (relative to the configuration's folder)", f)
        rel = [os.path.relpath(f, base) for f in files]
        if name == "net-file" and len(rel) != 1:
            raise ScenarioError(cfg, name, "one network file", value)
        return rel[0] if name == "net-file" else rel
    if name == "seed":
        return int(value)
    if name == "lateral-resolution":
        return float(value)
    return parse_time(value)  # step-length, begin, end (checked by read_config)


def sumo_options(options: dict, base: pathlib.Path, file: str) -> tuple[tuple[str, str], ...]:
    """``sim.options`` (SUMO option name -> value) as SUMO's command line wants them: canonical names,
    values as text, FILE values absolute (relative ones against ``base``, the scenario's folder).
    Refuses an option that is not SUMO's, one a ``[sim]`` key sets, one the plug-in owns, a bad value."""
    out = []
    for name, value in options.items():
        key = f'sim.options."{name}"' if "." in name else f"sim.options.{name}"
        try:
            opt = option(name)
        except OptionError as e:
            raise ScenarioError(file, key, e.expected, name) from None
        if opt.name in MAPPED:
            raise ScenarioError(file, key, f"the key sim.{MAPPED[opt.name]} (the plug-in sets --{opt.name} from it)",
                                show_got=False)
        why = owned(opt)
        if why is not None:
            raise ScenarioError(file, key, f"an option the plug-in does not set itself ({why})", value)
        text = _text(value)
        if text is None:
            raise ScenarioError(file, key, "a string, number, true/false or a list of strings", value)
        try:
            check_value(opt.name, text)
        except OptionError as e:
            raise ScenarioError(file, key, e.expected, value) from None
        if opt.type == "FILE":
            text = ",".join(str((base / f).resolve()) for f in split_files(text))
        out.append((opt.name, text))
    return tuple(out)


def _text(value) -> str | None:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, str)) or (isinstance(value, float) and math.isfinite(value)):
        return str(value)
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return ",".join(value)
    return None
