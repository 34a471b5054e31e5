//! The ATmega2560's registers this firmware uses (data-space addresses, datasheet §33 "Register
//! Summary") and their bits, with volatile access.

/// Port B: PB7 is the Mega's LED "L" (pin 13), high while a tick is being sampled.
pub const DDRB: u16 = 0x24;
pub const PORTB: u16 = 0x25;
pub const TICK_PIN: u8 = 1 << 7;

/// Port E: PE4 (pin 2) is CTS from the USB-serial adapter, PE5 (pin 3) the flow-control strap.
pub const PINE: u16 = 0x2C;
pub const PORTE: u16 = 0x2E;
pub const CTS_PIN: u8 = 1 << 4;
pub const STRAP_PIN: u8 = 1 << 5;

/// Sleep mode control: SE with SM = 000 is idle mode (timers, ADC and USART keep running).
pub const SMCR: u16 = 0x53;
pub const SMCR_IDLE: u8 = 0x01;

/// Reset cause, cleared at boot.
pub const MCUSR: u16 = 0x54;
/// Watchdog control (WDTCSR, 0x60, written in assembly): WDCE | WDE opens the 4-cycle window;
/// WDE | WDP1 | WDP0 is a 120 ms reset.
pub const WDT_CHANGE: u8 = 0x18;
pub const WDT_RESET_120MS: u8 = 0x0B;

/// Timer/Counter1: CTC on OCR1A (WGM12), clock/8 (CS11): 2 MHz counts.
pub const TIMSK1: u16 = 0x6F;
pub const OCIE1A: u8 = 1 << 1;
pub const TCCR1A: u16 = 0x80;
pub const TCCR1B: u16 = 0x81;
pub const TCCR1B_CTC_DIV8: u8 = 0x08 | 0x02;
pub const OCR1AL: u16 = 0x88;
pub const OCR1AH: u16 = 0x89;

/// ADC: AVCC reference; enabled, interrupt on completion, clock/128 (125 kHz at 16 MHz).
pub const ADCL: u16 = 0x78;
pub const ADCH: u16 = 0x79;
pub const ADCSRA: u16 = 0x7A;
pub const ADCSRB: u16 = 0x7B;
pub const ADMUX: u16 = 0x7C;
pub const DIDR0: u16 = 0x7E;
pub const ADMUX_AVCC: u8 = 0x40;
pub const ADCSRA_ON: u8 = 0x80 | 0x08 | 0x07;
pub const ADSC: u8 = 1 << 6;

/// USART0 (pins 0/1, wired to the Mega's USB bridge).
pub const UCSR0A: u16 = 0xC0;
pub const UCSR0B: u16 = 0xC1;
pub const UCSR0C: u16 = 0xC2;
pub const UBRR0L: u16 = 0xC4;
pub const UBRR0H: u16 = 0xC5;
pub const UDR0: u16 = 0xC6;
pub const U2X0: u8 = 1 << 1;
pub const UDRE0: u8 = 1 << 5;
pub const UDRIE0: u8 = 1 << 5;
/// RXCIE0 | RXEN0 | TXEN0.
pub const UCSR0B_ON: u8 = 0x80 | 0x10 | 0x08;
/// Asynchronous, no parity, 1 stop bit, 8 data bits.
pub const UCSR0C_8N1: u8 = 0x06;

/// Reads a register.
///
/// # Safety
/// `addr` must be one of the registers above.
#[inline(always)]
pub unsafe fn read(addr: u16) -> u8 {
    core::ptr::read_volatile(addr as *const u8)
}

/// Writes a register.
///
/// # Safety
/// `addr` must be one of the registers above, and the write must be one this firmware intends.
#[inline(always)]
pub unsafe fn write(addr: u16, value: u8) {
    core::ptr::write_volatile(addr as *mut u8, value);
}

/// Sets `bits` in a register (read, modify, write: only from code interrupts cannot preempt).
///
/// # Safety
/// As [`write`].
#[inline(always)]
pub unsafe fn set(addr: u16, bits: u8) {
    write(addr, read(addr) | bits);
}

/// Clears `bits` in a register (as [`set`]).
///
/// # Safety
/// As [`write`].
#[inline(always)]
pub unsafe fn clear(addr: u16, bits: u8) {
    write(addr, read(addr) & !bits);
}
