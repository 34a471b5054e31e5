//! Placeholder: the link benchmarks land with issue 13.
fn main() {}
