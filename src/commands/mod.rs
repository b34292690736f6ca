//! One module per `neo` subcommand.

pub mod bench;
pub mod compare;
pub mod render;
pub mod report;
pub mod scene;
pub mod trajectory;
pub mod view;
