"""Motions: action pages played as the robot plays them, pose-to-pose trajectories, and their checks."""
