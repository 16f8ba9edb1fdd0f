"""sumo."""
