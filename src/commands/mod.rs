//! One module per `neo` subcommand.

pub mod bench;
pub mod compare;
pub mod frames;
pub mod gen;
pub mod render;
pub mod report;
pub mod scene;
pub mod simulate;
pub mod trajectory;
pub mod view;
