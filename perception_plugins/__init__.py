"""Perception plug-ins (stereo referencing, multi-view models, stereo visual odometry), registered as entry
points in the `auv.perception` group and loaded by name. They import neither the simulator nor `planners`.
"""
