"""Simulated worlds: seabed height fields, subsea objects as they truly lie, currents."""
