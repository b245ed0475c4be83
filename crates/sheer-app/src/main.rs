//! The `sheer` binary.
fn main() {}
