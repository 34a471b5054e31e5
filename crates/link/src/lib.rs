//! The authenticated link to the manipulator controller. Work in progress (issue 13).
#![no_std]
