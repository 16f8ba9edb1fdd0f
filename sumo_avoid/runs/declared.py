"""What a run of a scenario writes, from the declarations alone (nothing runs): the names of its
metrics and every key they can write to ``metrics.json``, and the names of its plots."""
from __future__ import annotations

from sumo_avoid import plots
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.types import Keys
from sumo_avoid.metrics import STANDARD, declared_keys
from sumo_avoid.rollout.assemble import layer_plan


def metric_names(scn) -> tuple[str, ...]:
    """The standard set (the summary, plots, ledger and suites read it), what the controller declares
    (``metrics``), then what the scenario adds (``output.metrics``); each once, in that order."""
    names = STANDARD + CONTROLLERS[scn.spec.ego.controller].factory.metrics + scn.spec.output.metrics
    return tuple(dict.fromkeys(names))


def metric_keys(scn) -> Keys:
    """Every key a run of ``scn`` can write to ``metrics.json``: the keys of its metrics
    (:func:`metric_names`), the plug-ins' counters among them (the ``stats_keys`` of its controller
    and layers, monitors included; sensors and actuators write none)."""
    stats = Keys()
    for cls in (CONTROLLERS[scn.spec.ego.controller].factory, *(e.factory for e, _, _ in layer_plan(scn))):
        stats = stats | cls.stats_keys
    return declared_keys(metric_names(scn), scn, stats)


def plot_names(scn) -> tuple[str, ...]:
    """The figures of a run (:data:`sumo_avoid.plots.PLOTS`): the standard ones, ``arena`` when the
    scenario has an [arena] or obstacles, then those the controller declares (``plots``, optional)."""
    spec = scn.spec
    scene = ("arena",) if spec.arena is not None or spec.obstacles else ()
    declared = getattr(CONTROLLERS[spec.ego.controller].factory, "plots", ())
    return tuple(dict.fromkeys(plots.STANDARD + scene + tuple(declared)))
