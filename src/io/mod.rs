//! Files in and out: configuration, trajectories, plots.
