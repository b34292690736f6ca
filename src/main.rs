//! The `neo` command line.

fn main() {
    println!("neo");
}
