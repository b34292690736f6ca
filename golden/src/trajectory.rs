//! Camera trajectories at 30 fps: orbit, walk/fly-through and hand-held shake.
