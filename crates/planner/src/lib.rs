//! Where the finger goes: tactile-only scan rows (the paper's eq. 1 and 2), targeted slides across
//! detected candidates, their order, and time estimates. Work in progress (issue 13).
