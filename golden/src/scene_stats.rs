//! Scene statistics for `neo scene info`.
