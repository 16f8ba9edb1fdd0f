"""Gymnasium and PettingZoo environments of the scenarios (optional extra ``[gym]``; docs/gym.md):
:class:`SumoAvoidEnv` for one ego, :class:`SumoAvoidParallelEnv` for every ego of a flock or a
formation, the reward's :class:`RewardWeights`. A trained or scripted policy runs back in
``sumo-avoid run`` / ``batch`` / ``suite`` as the ``policy`` controller (:mod:`sumo_avoid.control.policy`)."""
from sumo_avoid.gym.env import SumoAvoidEnv
from sumo_avoid.gym.parallel import SumoAvoidParallelEnv
from sumo_avoid.gym.reward import RewardWeights

__all__ = ["RewardWeights", "SumoAvoidEnv", "SumoAvoidParallelEnv"]
