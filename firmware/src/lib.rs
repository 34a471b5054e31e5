//! Sampling firmware of the crackbot fibre-optic finger.
//!
//! A 400 Hz timer interrupt calls [`Sampler::tick`]: it reads the four channels D1, D2, D3 and P
//! once, builds a [`Frame`] (sequence number, device timestamp, raw counts, saturation and overrun
//! flags) and queues its [`WIRE_LEN`] wire bytes in a fixed-size ring buffer. [`Sampler::pump`]
//! moves queued bytes to the UART until the UART would block; call it from the main loop or the
//! UART's TX-empty interrupt. Nothing ever blocks: when the UART cannot keep up, whole frames are
//! dropped (never parts of one), the gap shows in the sequence numbers and the next frame sent
//! carries the overrun flag.
//!
//! # Hardware
//! The converter is anything that implements [`SampleAdc`]: the board image for the Arduino Mega
//! 2560 (`firmware/mega2560`) uses the ATmega2560's own 10-bit ADC, interrupt-driven; boards
//! without a good ADC can use an external MCP3008 over SPI ([`Mcp3008`], any embedded-hal 1.0
//! [`SpiDevice`](embedded_hal::spi::SpiDevice); embedded-hal 1.0 has no ADC trait). The UART is
//! any `embedded_hal_nb::serial::Write<u8>`. The host's commands on the UART's receive line are
//! read by [`command::CommandReader`].
//!
//! # Guarantees
//! `no_std`, no allocation, no `unsafe`, no panics on any input (counters wrap).
//!
//! # Example
//! ```
//! use core::convert::Infallible;
//! use crackbot_firmware::{SampleAdc, Sampler};
//! use embedded_hal_nb::serial::{ErrorKind, ErrorType, Write};
//!
//! struct FixedAdc;
//! impl SampleAdc for FixedAdc {
//!     type Error = Infallible;
//!     fn read_all(&mut self) -> Result<[u16; 4], Infallible> {
//!         Ok([660, 440, 720, 500])
//!     }
//! }
//!
//! struct Wire(Vec<u8>);
//! impl ErrorType for Wire {
//!     type Error = ErrorKind;
//! }
//! impl Write<u8> for Wire {
//!     fn write(&mut self, byte: u8) -> nb::Result<(), ErrorKind> {
//!         self.0.push(byte);
//!         Ok(())
//!     }
//!     fn flush(&mut self) -> nb::Result<(), ErrorKind> {
//!         Ok(())
//!     }
//! }
//!
//! let mut sampler: Sampler<_, _, 64> = Sampler::new(FixedAdc, Wire(Vec::new()));
//! sampler.tick(0); // from the 400 Hz timer interrupt
//! sampler.pump(); // from the main loop / TX-empty interrupt
//! assert_eq!(sampler.uart_mut().0.len(), crackbot_protocol::WIRE_LEN);
//! assert_eq!(sampler.stats().frames_queued, 1);
//! ```
#![no_std]

pub mod command;

use crackbot_protocol::{Channel, Flags, Frame, WIRE_LEN};
use embedded_hal::spi::SpiDevice;
use heapless::Deque;

/// Full scale of the 10-bit ADC (Arduino Mega ADC / MCP3008). A reading of 0 or `>= ADC_MAX` is
/// at a rail and flagged as saturated.
pub const ADC_MAX: u16 = 1023;

/// Reads the four channels D1, D2, D3, P once.
pub trait SampleAdc {
    /// Error of a failed read.
    type Error: core::fmt::Debug;
    /// Raw counts of D1, D2, D3, P, in that order.
    fn read_all(&mut self) -> Result<[u16; 4], Self::Error>;
}

/// Error of an [`Mcp3008`] read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Mcp3008Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// The channel map names an input that does not exist (the MCP3008 has inputs 0..=7).
    InvalidChannel(u8),
}

/// MCP3008 8-input 10-bit SPI ADC, read single-ended through an embedded-hal 1.0 `SpiDevice`
/// (SPI mode 0, at most 1.35 MHz at 2.7 V / 3.6 MHz at 5 V).
///
/// One conversion is one 3-byte transfer: `[0x01, 0x80 | input << 4, 0x00]` (start bit;
/// single-ended, input number; don't care); the result is the low 2 bits of the second byte
/// received followed by the third byte.
#[derive(Debug)]
pub struct Mcp3008<SPI> {
    spi: SPI,
    channel_map: [u8; 4],
}

impl<SPI> Mcp3008<SPI> {
    /// Driver for the chip behind `spi`; `channel_map` gives the MCP3008 input (0..=7) wired to
    /// D1, D2, D3 and P. An input above 7 is reported by [`SampleAdc::read_all`] as
    /// [`Mcp3008Error::InvalidChannel`].
    pub fn new(spi: SPI, channel_map: [u8; 4]) -> Self {
        Mcp3008 { spi, channel_map }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

impl<SPI: SpiDevice> SampleAdc for Mcp3008<SPI> {
    type Error = Mcp3008Error<SPI::Error>;

    fn read_all(&mut self) -> Result<[u16; 4], Self::Error> {
        // Check the whole map first so a bad map never starts a transfer.
        if let Some(&input) = self.channel_map.iter().find(|&&input| input > 7) {
            return Err(Mcp3008Error::InvalidChannel(input));
        }
        let mut values = [0u16; 4];
        for (value, &input) in values.iter_mut().zip(&self.channel_map) {
            let mut buf = [0x01, 0x80 | (input << 4), 0x00];
            self.spi
                .transfer_in_place(&mut buf)
                .map_err(Mcp3008Error::Spi)?;
            *value = (u16::from(buf[1] & 0x03) << 8) | u16::from(buf[2]);
        }
        Ok(values)
    }
}

/// Counters of a [`Sampler`]; all wrap at `u32::MAX`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FirmwareStats {
    /// Calls of [`Sampler::tick`].
    pub ticks: u32,
    /// Frames whose bytes went into the ring buffer.
    pub frames_queued: u32,
    /// Frames dropped because the ring buffer had no room for all their bytes.
    pub frames_dropped: u32,
    /// Ticks without a frame because the ADC read failed.
    pub adc_errors: u32,
    /// UART writes that failed with an error other than `WouldBlock` (the byte is retried).
    pub uart_errors: u32,
}

/// The sampling loop: ADC → frame → ring buffer of `TX` bytes → UART.
pub struct Sampler<A, U, const TX: usize> {
    adc: A,
    uart: U,
    tx: Deque<u8, TX>,
    next_seq: u16,
    overrun_pending: bool,
    stats: FirmwareStats,
}

impl<A: SampleAdc, U: embedded_hal_nb::serial::Write<u8>, const TX: usize> Sampler<A, U, TX> {
    /// A sampler whose first frame has sequence number 0. `TX` below [`WIRE_LEN`] can hold no
    /// frame; size it for at least two frames to absorb UART jitter.
    pub fn new(adc: A, uart: U) -> Self {
        Sampler {
            adc,
            uart,
            tx: Deque::new(),
            next_seq: 0,
            overrun_pending: false,
            stats: FirmwareStats::default(),
        }
    }

    /// Called by the 400 Hz timer interrupt with the device clock `now_us`.
    ///
    /// Reads the ADC and builds a frame with the next sequence number; the sequence number is
    /// consumed on every tick, even when no frame goes out, so the host sees the gap. Sets the
    /// saturation flag of each channel at 0 or `>= ADC_MAX`. Queues the frame's wire bytes if
    /// all of them fit in the ring buffer, otherwise drops the whole frame, counts it and sets
    /// the overrun flag on the next frame that is queued. A failed ADC read is counted and sends
    /// nothing (it does not set the overrun flag). Then calls [`pump`](Self::pump). Never blocks.
    pub fn tick(&mut self, now_us: u32) {
        self.stats.ticks = self.stats.ticks.wrapping_add(1);
        let seq = self.next_seq;
        self.next_seq = seq.wrapping_add(1);
        match self.adc.read_all() {
            Ok(channels) => {
                let mut flags = Flags::empty();
                for (channel, &value) in Channel::ALL.into_iter().zip(&channels) {
                    flags.set_saturated(channel, value == 0 || value >= ADC_MAX);
                }
                self.queue(Frame {
                    seq,
                    timestamp_us: now_us,
                    channels,
                    flags,
                });
            }
            Err(_) => self.stats.adc_errors = self.stats.adc_errors.wrapping_add(1),
        }
        self.pump();
    }

    fn queue(&mut self, mut frame: Frame) {
        frame.flags.set_overrun(self.overrun_pending);
        if self.push_whole(&frame) {
            self.overrun_pending = false;
            self.stats.frames_queued = self.stats.frames_queued.wrapping_add(1);
        } else {
            self.stats.frames_dropped = self.stats.frames_dropped.wrapping_add(1);
            self.overrun_pending = true;
        }
    }

    /// Puts all [`WIRE_LEN`] wire bytes of `frame` in the ring buffer, or none when they do not
    /// all fit; returns whether they went in.
    fn push_whole(&mut self, frame: &Frame) -> bool {
        if self.tx.capacity().saturating_sub(self.tx.len()) < WIRE_LEN {
            return false;
        }
        for byte in frame.to_wire() {
            // Cannot fail: room for all WIRE_LEN bytes was checked above.
            let _ = self.tx.push_back(byte);
        }
        true
    }

    /// Queues a frame built elsewhere (the board's encode command, [`command`]) whole, or not at
    /// all when the ring buffer has no room for its [`WIRE_LEN`] bytes: returns whether it was
    /// queued. Touches neither the sequence numbers, the counters nor the overrun flag of the
    /// sampled frames. Then calls [`pump`](Self::pump).
    pub fn send_frame(&mut self, frame: &Frame) -> bool {
        let queued = self.push_whole(frame);
        self.pump();
        queued
    }

    /// Moves queued bytes to the UART until it answers `WouldBlock` or the queue is empty. On any
    /// other UART error the byte stays queued (it is retried on the next call), the error is
    /// counted and the call returns.
    pub fn pump(&mut self) {
        while let Some(&byte) = self.tx.front() {
            match self.uart.write(byte) {
                Ok(()) => {
                    self.tx.pop_front();
                }
                Err(nb::Error::WouldBlock) => return,
                Err(nb::Error::Other(_)) => {
                    self.stats.uart_errors = self.stats.uart_errors.wrapping_add(1);
                    return;
                }
            }
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> FirmwareStats {
        self.stats
    }

    /// Bytes waiting in the ring buffer for the UART.
    pub fn queued_bytes(&self) -> usize {
        self.tx.len()
    }

    /// The ADC, e.g. to reconfigure it.
    pub fn adc_mut(&mut self) -> &mut A {
        &mut self.adc
    }

    /// The UART, e.g. to service its interrupt flags.
    pub fn uart_mut(&mut self) -> &mut U {
        &mut self.uart
    }

    /// Gives the ADC and the UART back; queued bytes are discarded.
    pub fn release(self) -> (A, U) {
        (self.adc, self.uart)
    }
}
