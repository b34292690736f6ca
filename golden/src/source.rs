//! Scene sources: a file path or a `synthetic:NAME?gaussians=N&seed=S` spec.
