//! crackbot's sampling firmware for the Arduino Mega 2560 (ATmega2560, 16 MHz), the board of the
//! papers: the four Keyence amplifier outputs on A0..A3 are sampled at 400 Hz by the on-chip
//! 10-bit ADC and sent as `crackbot-protocol` frames on USART0 (115 200 baud, the USB port).
//!
//! The work is the `crackbot-firmware` library's [`Sampler`]; this file only wires it to the
//! chip's interrupts:
//! * Timer1 compare A (400 Hz): stamp the tick, start converting A0.
//! * ADC complete: store the conversion, start the next input; after A3, `Sampler::tick`.
//! * USART0 data register empty: `Sampler::pump`.
//! * USART0 receive: the host's commands (`crackbot_firmware::command`).
//!
//! The main loop only sleeps. The watchdog (120 ms) is kicked after every tick, so a stalled
//! sampling chain resets the board, which the host sees as the sequence numbers starting at 0.
#![no_std]
#![no_main]
#![feature(abi_avr_interrupt, asm_experimental_arch)]

mod peripherals;
mod regs;

use crackbot_firmware::command::{Command, CommandReader};
use crackbot_firmware::Sampler;
use crackbot_protocol::SAMPLE_PERIOD_US;

use peripherals::{Conversions, Usart0};

/// Bytes of the transmit ring buffer: five frames.
const TX_BYTES: usize = 5 * crackbot_protocol::WIRE_LEN;

/// Everything the interrupt handlers share.
struct Board {
    sampler: Sampler<Conversions, Usart0, TX_BYTES>,
    commands: CommandReader,
    /// Input being converted (0..=3).
    channel: u8,
    /// Device time of the tick being sampled, µs (wraps).
    stamp_us: u32,
}

static mut BOARD: Option<Board> = None;

/// Runs `f` on the board's state.
///
/// # Safety
/// Only from interrupt handlers: the AVR clears the global interrupt flag on entry and no handler
/// here sets it again, so they never nest and this is the only live reference.
unsafe fn with_board(f: impl FnOnce(&mut Board)) {
    if let Some(board) = BOARD.as_mut() {
        f(board);
    }
}

#[no_mangle]
pub extern "C" fn main() -> ! {
    // SAFETY: interrupts are off until `enable_interrupts`; nothing else runs.
    unsafe {
        peripherals::watchdog_start();
        peripherals::tick_pin_init();
        let flow_control = peripherals::flow_control_strapped();
        peripherals::usart0_init();
        peripherals::adc_init();
        BOARD = Some(Board {
            sampler: Sampler::new(Conversions([0; 4]), Usart0 { flow_control }),
            commands: CommandReader::new(),
            channel: 0,
            stamp_us: 0u32.wrapping_sub(SAMPLE_PERIOD_US),
        });
        peripherals::timer1_init();
        peripherals::enable_interrupts();
    }
    loop {
        peripherals::sleep();
    }
}

/// TIMER1_COMPA: a new tick; its timestamp is the moment A0's conversion starts.
#[no_mangle]
pub unsafe extern "avr-interrupt" fn __vector_17() {
    peripherals::tick_pin(true);
    with_board(|board| {
        board.stamp_us = board.stamp_us.wrapping_add(SAMPLE_PERIOD_US);
        board.channel = 0;
    });
    peripherals::adc_start(0);
}

/// ADC: one input converted; the next, or the frame.
#[no_mangle]
pub unsafe extern "avr-interrupt" fn __vector_29() {
    let value = peripherals::adc_result();
    with_board(|board| {
        let channel = board.channel;
        board.sampler.adc_mut().0[usize::from(channel & 3)] = value;
        if channel < 3 {
            board.channel = channel + 1;
            peripherals::adc_start(channel + 1);
        } else {
            board.sampler.tick(board.stamp_us);
            peripherals::watchdog_kick();
            peripherals::tick_pin(false);
        }
    });
}

/// USART0_UDRE: room for the next byte.
#[no_mangle]
pub unsafe extern "avr-interrupt" fn __vector_26() {
    with_board(|board| {
        board.sampler.pump();
        if board.sampler.queued_bytes() == 0 {
            peripherals::usart0_quiet();
        }
    });
}

/// USART0_RX: a byte from the host.
#[no_mangle]
pub unsafe extern "avr-interrupt" fn __vector_25() {
    let byte = peripherals::usart0_received();
    with_board(|board| {
        if let Some(Ok(Command::Encode(frame))) = board.commands.push(byte) {
            board.sampler.send_frame(&frame);
        }
    });
}

/// A panic cannot happen in this code (the sampler is panic-free); if one did, the loop starves
/// the watchdog and the board resets within 120 ms.
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
