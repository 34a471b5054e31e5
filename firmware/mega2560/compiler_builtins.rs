//! Marker crate: rustc wants a `compiler_builtins` crate; on AVR the routines come from avr-gcc's libgcc at link time.
#![feature(compiler_builtins)]
#![compiler_builtins]
#![no_std]
