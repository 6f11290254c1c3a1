"""The PNG figures: poses as stick figures, cost curves, motions, walks (CoM, ZMP, CoP tracks), steered paths and
tuning fronts; rendered without a display (Agg), the same bytes in a forked process."""
