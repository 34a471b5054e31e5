//! Placeholder: the planner benchmarks land with issue 13.
fn main() {}
