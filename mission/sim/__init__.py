"""The simulator: a kinematic vehicle with sensors in a seeded world, behind the `VehicleInterface`."""
