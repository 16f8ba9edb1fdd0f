"""Path planning (seed 004, SPEC §4): the GA path planner (:mod:`.ga`, compiled parts in
:mod:`.kernels`), the obstacle map one ego's radar reveals (:mod:`.radar_map`) and the
pure-pursuit tracker (:mod:`.pursuit`). Pure numpy (and numba); no SUMO. The controller that
wires them to the rollout is :mod:`sumo_avoid.control.ga_planner.ga_planner`."""
