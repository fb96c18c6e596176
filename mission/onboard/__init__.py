"""The onboard executive: `auv run` flies a mission on a real vehicle (an `auv.vehicles` adapter) in wall-clock
time, with the same executive, agents, safety monitors and run folder as `auv simulate`."""
