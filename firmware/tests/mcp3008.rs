//! The MCP3008 driver against a mock SPI device that behaves like the chip.

use std::convert::Infallible;

use crackbot_firmware::{Mcp3008, Mcp3008Error, SampleAdc, Sampler};
use crackbot_protocol::{Decoder, Frame};
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// An MCP3008 on an SPI bus: decodes the 3-byte single-ended command and answers with the 10-bit
/// value of the addressed input from `inputs`. The bits the chip leaves undefined in the second
/// byte are set to 1, so a driver that does not mask them reads wrong values.
struct Mcp3008Chip {
    inputs: [u16; 8],
    /// Inputs converted, in order.
    conversions: Vec<u8>,
    /// Make every transfer fail.
    fail: bool,
}

impl Mcp3008Chip {
    fn new(inputs: [u16; 8]) -> Self {
        Mcp3008Chip {
            inputs,
            conversions: Vec::new(),
            fail: false,
        }
    }
}

impl ErrorType for Mcp3008Chip {
    type Error = ErrorKind;
}

impl SpiDevice for Mcp3008Chip {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        if self.fail {
            return Err(ErrorKind::ModeFault);
        }
        for op in operations {
            let Operation::TransferInPlace(buf) = op else {
                panic!("the driver should use one transfer_in_place per conversion");
            };
            assert_eq!(buf.len(), 3, "an MCP3008 conversion is 3 bytes");
            assert_eq!(buf[0], 0x01, "first byte must carry the start bit");
            assert_eq!(buf[1] & 0x80, 0x80, "SGL/DIFF must select single-ended");
            assert_eq!(
                buf[1] & 0x0F,
                0,
                "the low nibble of byte 2 is don't care and sent as 0"
            );
            let input = (buf[1] >> 4) & 0x07;
            let value = self.inputs[usize::from(input)] & 0x3FF;
            self.conversions.push(input);
            buf[0] = 0xFF;
            buf[1] = 0xF8 | (value >> 8) as u8; // null bit is 0, higher bits undefined
            buf[2] = value as u8;
        }
        Ok(())
    }
}

const INPUTS: [u16; 8] = [660, 1023, 0, 441, 722, 256, 513, 999];

#[test]
fn reads_the_mapped_inputs_in_channel_order() {
    let mut adc = Mcp3008::new(Mcp3008Chip::new(INPUTS), [0, 1, 2, 3]);
    assert_eq!(adc.read_all().expect("read"), [660, 1023, 0, 441]);

    let mut adc = Mcp3008::new(Mcp3008Chip::new(INPUTS), [7, 4, 6, 5]);
    assert_eq!(adc.read_all().expect("read"), [999, 722, 513, 256]);
    assert_eq!(adc.read_all().expect("read"), [999, 722, 513, 256]);
    assert_eq!(adc.release().conversions, [7, 4, 6, 5, 7, 4, 6, 5]);
}

#[test]
fn invalid_channel_map_is_an_error_without_any_transfer() {
    let mut adc = Mcp3008::new(Mcp3008Chip::new(INPUTS), [0, 1, 8, 3]);
    assert_eq!(adc.read_all(), Err(Mcp3008Error::InvalidChannel(8)));
    let mut adc = Mcp3008::new(adc.release(), [255, 0, 0, 0]);
    assert_eq!(adc.read_all(), Err(Mcp3008Error::InvalidChannel(255)));
    assert!(adc.release().conversions.is_empty());
}

#[test]
fn spi_error_is_reported() {
    let mut chip = Mcp3008Chip::new(INPUTS);
    chip.fail = true;
    let mut adc = Mcp3008::new(chip, [0, 1, 2, 3]);
    assert_eq!(adc.read_all(), Err(Mcp3008Error::Spi(ErrorKind::ModeFault)));
}

/// A UART that takes every byte at once.
struct Wire(Vec<u8>);

impl embedded_hal_nb::serial::ErrorType for Wire {
    type Error = Infallible;
}

impl embedded_hal_nb::serial::Write<u8> for Wire {
    fn write(&mut self, byte: u8) -> nb::Result<(), Infallible> {
        self.0.push(byte);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), Infallible> {
        Ok(())
    }
}

#[test]
fn sampler_sends_mcp3008_readings() {
    let adc = Mcp3008::new(Mcp3008Chip::new(INPUTS), [0, 3, 4, 7]);
    let mut sampler: Sampler<_, _, 64> = Sampler::new(adc, Wire(Vec::new()));
    sampler.tick(0);
    sampler.tick(2500);
    let (_, wire) = sampler.release();
    let mut frames: Vec<Frame> = Vec::new();
    Decoder::new().feed(&wire.0, |r| frames.push(r.expect("valid frame")));
    assert_eq!(frames.len(), 2);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame.seq, k as u16);
        assert_eq!(frame.channels, [660, 441, 722, 999]);
        assert_eq!(frame.flags.0, 0);
    }
}
