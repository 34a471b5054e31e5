//! Set-up and use of the ATmega2560's peripherals: USART0 as the sampler's UART, the on-chip ADC
//! as its converter, Timer1 as the 400 Hz tick, the watchdog. Every function here is called with
//! interrupts disabled (at boot, or from an interrupt handler: the AVR does not nest them).

use core::convert::Infallible;

use crackbot_firmware::SampleAdc;
use embedded_hal_nb::serial::{ErrorType, Write};

use crate::regs::{self, *};

/// CPU clock of the Arduino Mega 2560 (its 16 MHz crystal).
pub const F_CPU: u32 = 16_000_000;
/// Timer1 counts at F_CPU / 8 = 2 MHz; 5000 counts are 2.5 ms (400 Hz, exact).
pub const TICK_COUNTS: u16 = (F_CPU / 8 / crackbot_protocol::SAMPLE_RATE_HZ) as u16;
/// USART0 divisor with U2X0: 16 MHz / (8 × (16 + 1)) = 117 647 baud, 2.1 % above 115 200 (the
/// Arduino core's setting; the Mega's USB bridge runs from the same crystal and matches it).
pub const UBRR_115200: u8 = ((F_CPU + 4 * 115_200) / (8 * 115_200) - 1) as u8;

/// Configures USART0 at 115 200 baud 8N1, receive interrupt on; the data-register-empty
/// interrupt is switched on by [`Usart0::write`] whenever a byte must wait.
pub unsafe fn usart0_init() {
    // U2X0 before the divisor: the chip does not care, simavr computes the baud rate when UBRR0L
    // is written.
    write(UCSR0A, U2X0);
    write(UBRR0H, 0);
    write(UBRR0L, UBRR_115200);
    write(UCSR0C, UCSR0C_8N1);
    write(UCSR0B, UCSR0B_ON);
}

/// The last byte received on USART0.
pub unsafe fn usart0_received() -> u8 {
    read(UDR0)
}

/// Switches off the data-register-empty interrupt (nothing left to send, or CTS holds us).
pub unsafe fn usart0_quiet() {
    clear(UCSR0B, UDRIE0);
}

/// USART0 as the sampler's non-blocking UART. With `flow_control`, a high CTS input (PE4, the
/// adapter's RTS#) holds transmission: bytes stay in the sampler's ring buffer, which then drops
/// whole frames and flags the overrun, exactly as when the line is too slow.
pub struct Usart0 {
    pub flow_control: bool,
}

impl ErrorType for Usart0 {
    type Error = Infallible;
}

impl Write<u8> for Usart0 {
    fn write(&mut self, byte: u8) -> nb::Result<(), Infallible> {
        // SAFETY: called only by the sampler, from interrupt handlers (see `crate::with_board`).
        unsafe {
            if self.flow_control && read(PINE) & CTS_PIN != 0 {
                usart0_quiet();
                return Err(nb::Error::WouldBlock);
            }
            if read(UCSR0A) & UDRE0 == 0 {
                set(UCSR0B, UDRIE0);
                return Err(nb::Error::WouldBlock);
            }
            write(UDR0, byte);
            set(UCSR0B, UDRIE0);
        }
        Ok(())
    }

    fn flush(&mut self) -> nb::Result<(), Infallible> {
        Ok(())
    }
}

/// The four channels' latest conversions (ADC0..ADC3 = D1, D2, D3, P on pins A0..A3), filled by
/// the ADC interrupt and read by the sampler once all four are in.
pub struct Conversions(pub [u16; 4]);

impl SampleAdc for Conversions {
    type Error = Infallible;
    fn read_all(&mut self) -> Result<[u16; 4], Infallible> {
        Ok(self.0)
    }
}

/// ADC on, AVCC reference, 125 kHz conversion clock (104 µs a conversion), interrupt on
/// completion; the digital inputs of A0..A3 off.
pub unsafe fn adc_init() {
    write(ADCSRB, 0);
    write(DIDR0, 0x0F);
    write(ADMUX, ADMUX_AVCC);
    write(ADCSRA, ADCSRA_ON);
}

/// Starts one conversion of input `channel` (0..=3).
pub unsafe fn adc_start(channel: u8) {
    write(ADMUX, ADMUX_AVCC | (channel & 0x07));
    set(ADCSRA, ADSC);
}

/// The finished conversion (ADCL must be read before ADCH).
pub unsafe fn adc_result() -> u16 {
    let low = read(ADCL);
    let high = read(ADCH);
    (u16::from(high) << 8) | u16::from(low)
}

/// Timer1 in CTC mode: a compare-match A interrupt every [`TICK_COUNTS`] counts (400 Hz).
pub unsafe fn timer1_init() {
    write(TCCR1A, 0);
    let top = TICK_COUNTS - 1;
    // 16-bit register: high byte first.
    write(OCR1AH, (top >> 8) as u8);
    write(OCR1AL, top as u8);
    write(TCCR1B, TCCR1B_CTC_DIV8);
    write(TIMSK1, OCIE1A);
}

/// The watchdog resets the chip if it is not kicked for 120 ms (48 ticks). The two writes must
/// come within 4 cycles of each other, hence the assembly.
pub unsafe fn watchdog_start() {
    regs::write(MCUSR, 0);
    // 0x60 is WDTCSR.
    core::arch::asm!(
        "wdr",
        "sts 0x60, {open}",
        "sts 0x60, {set}",
        open = in(reg) WDT_CHANGE,
        set = in(reg) WDT_RESET_120MS,
    );
}

/// Kicks the watchdog.
pub fn watchdog_kick() {
    // SAFETY: `wdr` only restarts the watchdog's count.
    unsafe { core::arch::asm!("wdr") };
}

/// The LED pin (PB7) as an output; high while a tick is sampled (a steady glow while streaming,
/// and what the emulator times the tick by).
pub unsafe fn tick_pin_init() {
    set(DDRB, TICK_PIN);
}

/// Sets the tick pin high or low.
pub unsafe fn tick_pin(on: bool) {
    if on {
        set(PORTB, TICK_PIN);
    } else {
        clear(PORTB, TICK_PIN);
    }
}

/// Pull-ups on CTS (PE4) and the strap (PE5); true when the strap is tied to ground: hardware
/// flow control on.
pub unsafe fn flow_control_strapped() -> bool {
    set(PORTE, CTS_PIN | STRAP_PIN);
    // Let the pull-up charge the pin before it is read.
    for _ in 0..16u8 {
        core::arch::asm!("nop");
    }
    read(PINE) & STRAP_PIN == 0
}

/// Idle sleep until the next interrupt.
pub fn sleep() {
    // SAFETY: idle mode stops only the CPU clock; any enabled interrupt wakes it.
    unsafe {
        write(SMCR, SMCR_IDLE);
        core::arch::asm!("sleep");
    }
}

/// Global interrupt enable.
pub unsafe fn enable_interrupts() {
    core::arch::asm!("sei");
}
