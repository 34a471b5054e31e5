/*
 * The crackbot board image on an emulated Arduino Mega 2560.
 *
 * simavr emulates the ATmega2560 cycle by cycle (16 MHz); this harness is the rest of the board
 * and the desk around it:
 *   - the four amplifier outputs: each ADC conversion the firmware starts on A0..A3 reads the next
 *     sample of a trace (raw counts, given in millivolts of a 5 V AVCC so that the chip's own
 *     conversion gives back exactly those counts);
 *   - the USB-serial bridge: USART0's bytes go to a new pseudo-terminal, the host's bytes come
 *     back to USART0's receiver. Like an FTDI adapter it has a 256-byte buffer and, when the
 *     board is strapped for it (PE5 low, the default here), holds the board's CTS (PE4) high
 *     while that buffer is full; with --no-flow-control it drops bytes instead, as the Mega's own
 *     16U2 bridge does;
 *   - time: emulated time is paced to the host's monotonic clock (the board runs at real time);
 *   - measurement: the firmware raises PB7 while it samples a tick; the harness counts the cycles
 *     the CPU was awake during each tick and during each 2.5 ms period.
 *
 * Signals: SIGUSR1 = power-on reset, SIGUSR2 = corrupt the next byte on the line,
 * SIGINT/SIGTERM = stop. At exit (and every second with --stats FILE) it writes its counters as
 * one JSON object to standard error (and to FILE).
 *
 * usage: crackbot-mega2560-emulator [--no-flow-control] [--stats FILE] TRACE.csv FIRMWARE.elf
 * The pseudo-terminal's path is the first line on standard output; the board powers up when the
 * terminal is first opened.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <simavr/avr_adc.h>
#include <simavr/avr_extint.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>

#define F_CPU 16000000ULL
#define PERIOD_CYCLES 40000ULL /* 2.5 ms */
#define AVCC_MV 5000
#define BRIDGE_SIZE 256
#define BRIDGE_HOLD 192 /* CTS high at this fill, low again at BRIDGE_RESUME */
#define BRIDGE_RESUME 64

typedef struct { uint16_t ch[4]; } sample_t;

static avr_t *avr;
static sample_t *trace;
static size_t trace_len, trace_pos;
static int flow_control = 1;
static int master_fd = -1;
static const char *stats_path;

static uint8_t bridge[BRIDGE_SIZE];
static size_t bridge_head, bridge_len;
static int cts_high;
static avr_irq_t *cts_irq, *strap_irq, *uart_in_irq;
/* Host → board: bytes read from the terminal, fed to USART0's receiver while its FIFO has room. */
static uint8_t to_board[64];
static size_t to_board_len, to_board_pos;
static int uart_rx_room = 1;

static volatile sig_atomic_t want_reset, want_corrupt, want_stop;

static struct {
    uint64_t ticks, bytes_out, bytes_dropped, bytes_in, cts_holds, resets, corrupted;
    uint64_t awake_cycles, samples_fed, uart_bytes;
    uint64_t vector_cycles[64]; /* awake cycles by the innermost running interrupt, 0 = main */
    uint64_t tick_cycles_max, tick_latency_max, period_awake_max;
} st;

/* Counters at the start of the current period (the tick pin's rising edge). */
static uint64_t period_cycle, period_awake, period_tick_cycles;
static int in_tick, have_period;

/* The tick's own work: Timer1 compare A and ADC complete handlers (vectors 17 and 29). */
static uint64_t tick_work(void) { return st.vector_cycles[17] + st.vector_cycles[29]; }

static void die(const char *what) {
    fprintf(stderr, "crackbot-mega2560-emulator: %s\n", what);
    exit(2);
}

/* ---- the trace ---------------------------------------------------------------------------- */

static void load_trace(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "crackbot-mega2560-emulator: cannot open the trace %s: %s\n", path,
                strerror(errno));
        exit(2);
    }
    size_t cap = 1024, line_no = 0;
    trace = malloc(cap * sizeof *trace);
    char line[256];
    while (fgets(line, sizeof line, f)) {
        line_no++;
        if (line[0] == '#' || line[0] == '\n' || line[0] == '\r') continue;
        if (line_no == 1 && (line[0] < '0' || line[0] > '9')) continue; /* a header */
        unsigned v[4];
        char extra;
        if (sscanf(line, "%u,%u,%u,%u %c", &v[0], &v[1], &v[2], &v[3], &extra) != 4) {
            fprintf(stderr,
                    "crackbot-mega2560-emulator: %s line %zu: expected four raw counts "
                    "D1,D2,D3,P, got: %s",
                    path, line_no, line);
            exit(2);
        }
        for (int i = 0; i < 4; i++) {
            if (v[i] > 1023) {
                fprintf(stderr,
                        "crackbot-mega2560-emulator: %s line %zu: count %u of channel %d is "
                        "above the 10-bit ADC's 1023\n",
                        path, line_no, v[i], i + 1);
                exit(2);
            }
        }
        if (trace_len == cap) trace = realloc(trace, (cap *= 2) * sizeof *trace);
        for (int i = 0; i < 4; i++) trace[trace_len].ch[i] = (uint16_t)v[i];
        trace_len++;
    }
    fclose(f);
    if (trace_len == 0) {
        fprintf(stderr, "crackbot-mega2560-emulator: %s holds no samples\n", path);
        exit(2);
    }
}

/* Millivolts that the ATmega's conversion, floor(mV × 1023 / AVCC), turns back into `count`. */
static uint32_t count_to_mv(uint16_t count) {
    return (uint32_t)(((uint64_t)count * AVCC_MV + 1022) / 1023);
}

/* A conversion starts: put the trace's value on that input. After P (A3) the next sample. */
static void on_adc_trigger(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)param;
    union { avr_adc_mux_t mux; uint32_t v; } e = {.v = value};
    unsigned src = e.mux.src;
    if (e.mux.kind != ADC_MUX_SINGLE || src > 3) return;
    avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + src),
                  count_to_mv(trace[trace_pos].ch[src]));
    if (src == 3) {
        trace_pos = (trace_pos + 1) % trace_len;
        st.samples_fed++;
    }
}

/* ---- the tick pin: timing ----------------------------------------------------------------- */

static void on_tick_pin(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)param;
    if (value && !in_tick) {
        in_tick = 1;
        if (have_period) {
            uint64_t awake = st.awake_cycles - period_awake;
            uint64_t work = tick_work() - period_tick_cycles;
            if (awake > st.period_awake_max) st.period_awake_max = awake;
            if (work > st.tick_cycles_max) st.tick_cycles_max = work;
        }
        have_period = 1;
        period_cycle = avr->cycle;
        period_awake = st.awake_cycles;
        period_tick_cycles = tick_work();
    } else if (!value && in_tick) {
        in_tick = 0;
        st.ticks++;
        uint64_t latency = avr->cycle - period_cycle;
        if (latency > st.tick_latency_max) st.tick_latency_max = latency;
    }
}

/* Cycles simavr skipped while the CPU slept during the current step (it adds 1 + how_long). */
static uint64_t step_slept;

static void on_sleep(avr_t *a, avr_cycle_count_t how_long) {
    (void)a;
    step_slept += 1 + how_long;
}

/* ---- the bridge --------------------------------------------------------------------------- */

static void set_cts(int high) {
    if (high == cts_high) return;
    cts_high = high;
    if (high) st.cts_holds++;
    avr_raise_irq(cts_irq, high);
}

static void on_uart_byte(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)param;
    uint8_t byte = (uint8_t)value;
    st.uart_bytes++;
    if (want_corrupt && byte != 0) {
        /* One byte inside a frame, never into a delimiter: exactly one frame is damaged. */
        want_corrupt = 0;
        byte ^= 0x5A;
        if (byte == 0) byte = 0xFF;
        st.corrupted++;
    }
    if (bridge_len == BRIDGE_SIZE) {
        st.bytes_dropped++;
        return;
    }
    bridge[(bridge_head + bridge_len) % BRIDGE_SIZE] = byte;
    bridge_len++;
    if (flow_control && bridge_len >= BRIDGE_HOLD) set_cts(1);
}

static void bridge_service(void) {
    while (bridge_len) {
        size_t run = bridge_len;
        if (bridge_head + run > BRIDGE_SIZE) run = BRIDGE_SIZE - bridge_head;
        ssize_t n = write(master_fd, bridge + bridge_head, run);
        if (n <= 0) break; /* EAGAIN: the host is not reading */
        st.bytes_out += (uint64_t)n;
        bridge_head = (bridge_head + (size_t)n) % BRIDGE_SIZE;
        bridge_len -= (size_t)n;
    }
    if (flow_control && bridge_len <= BRIDGE_RESUME) set_cts(0);
    /* The host's bytes, as fast as the receiver's FIFO takes them (simavr paces them out at the
     * baud rate and signals XOFF when the FIFO is full). */
    if (to_board_pos == to_board_len) {
        ssize_t n = read(master_fd, to_board, sizeof to_board);
        to_board_len = n > 0 ? (size_t)n : 0;
        to_board_pos = 0;
        st.bytes_in += to_board_len;
    }
    while (to_board_pos < to_board_len && uart_rx_room) avr_raise_irq(uart_in_irq, to_board[to_board_pos++]);
}

static void on_uart_xon(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)value;
    (void)param;
    uart_rx_room = 1;
}

static void on_uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param) {
    (void)irq;
    (void)value;
    (void)param;
    uart_rx_room = 0;
}

static int open_pty(void) {
    int fd = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0 || grantpt(fd) || unlockpt(fd)) die("cannot create a pseudo-terminal");
    /* Raw mode, set through the slave (the settings stay with the pair). */
    int slave = open(ptsname(fd), O_RDWR | O_NOCTTY);
    if (slave < 0) die("cannot open the pseudo-terminal's slave side");
    struct termios t;
    tcgetattr(slave, &t);
    cfmakeraw(&t);
    cfsetspeed(&t, B115200);
    tcsetattr(slave, TCSANOW, &t);
    close(slave);
    return fd;
}

/* ---- board, pins, reset ------------------------------------------------------------------- */

static void drive_inputs(void) {
    /* PE5 strap: low = flow control on; PE4 = CTS. */
    avr_ioport_external_t ext = {.name = 'E', .mask = 0x30,
                                 .value = (uint8_t)((flow_control ? 0 : 0x20) | (cts_high ? 0x10 : 0))};
    avr_ioctl(avr, AVR_IOCTL_IOPORT_SET_EXTERNAL('E'), &ext);
    avr_raise_irq(strap_irq, flow_control ? 0 : 1);
    avr_raise_irq(cts_irq, cts_high);
}

static void power_on_reset(void) {
    avr_reset(avr);
    trace_pos = 0;
    in_tick = 0;
    have_period = 0;
    drive_inputs();
    st.resets++;
}

static void on_signal(int sig) {
    if (sig == SIGUSR1) want_reset = 1;
    else if (sig == SIGUSR2) want_corrupt = 1;
    else want_stop = 1;
}

static void write_stats(FILE *f) {
    double seconds = (double)avr->cycle / (double)F_CPU;
    fprintf(f,
            "{\"emulated_s\": %.6f, \"cycles\": %llu, \"ticks\": %llu, \"samples_fed\": %llu, "
            "\"tick_cycles_max\": %llu, \"tick_cycles_mean\": %.1f, "
            "\"tick_latency_cycles_max\": %llu, \"period_awake_cycles_max\": %llu, "
            "\"uart_cycles_per_byte\": %.1f, \"period_cycles\": %llu, \"f_cpu_hz\": %llu, "
            "\"awake_fraction\": %.5f, \"uart_bytes\": %llu, \"bytes_out\": %llu, \"bytes_in\": %llu, "
            "\"bridge_dropped\": %llu, \"cts_holds\": %llu, \"resets\": %llu, "
            "\"corrupted\": %llu, \"flow_control\": %s}\n",
            seconds, (unsigned long long)avr->cycle, (unsigned long long)st.ticks,
            (unsigned long long)st.samples_fed, (unsigned long long)st.tick_cycles_max,
            st.ticks ? (double)tick_work() / (double)st.ticks : 0.0,
            (unsigned long long)st.tick_latency_max, (unsigned long long)st.period_awake_max,
            st.uart_bytes ? (double)st.vector_cycles[26] / (double)st.uart_bytes : 0.0,
            PERIOD_CYCLES, F_CPU,
            avr->cycle ? (double)st.awake_cycles / (double)avr->cycle : 0.0,
            (unsigned long long)st.uart_bytes,
            (unsigned long long)st.bytes_out, (unsigned long long)st.bytes_in,
            (unsigned long long)st.bytes_dropped, (unsigned long long)st.cts_holds,
            (unsigned long long)st.resets, (unsigned long long)st.corrupted,
            flow_control ? "true" : "false");
    fflush(f);
}

static void save_stats(void) {
    if (!stats_path) return;
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", stats_path);
    FILE *f = fopen(tmp, "w");
    if (!f) return;
    write_stats(f);
    fclose(f);
    rename(tmp, stats_path);
}

static uint64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ULL + (uint64_t)ts.tv_nsec;
}

static void usage(void) {
    fprintf(stderr,
            "usage: crackbot-mega2560-emulator [--no-flow-control] [--stats FILE] TRACE.csv "
            "FIRMWARE.elf\n");
    exit(2);
}

static void setup_board(const char *elf) {
    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    /* simavr reports what it loaded on standard output, where the first line must be the
     * pseudo-terminal's path: send it to standard error meanwhile. */
    fflush(stdout);
    int saved_stdout = dup(STDOUT_FILENO);
    dup2(STDERR_FILENO, STDOUT_FILENO);
    int failed = access(elf, R_OK) != 0 || elf_read_firmware(elf, &fw) != 0;
    if (failed) {
        fprintf(stderr, "crackbot-mega2560-emulator: cannot read the firmware %s\n", elf);
        exit(2);
    }
    avr = avr_make_mcu_by_name("atmega2560");
    if (!avr) die("this simavr has no atmega2560");
    avr_init(avr);
    fw.frequency = F_CPU;
    avr_load_firmware(avr, &fw);
    fflush(stdout);
    dup2(saved_stdout, STDOUT_FILENO);
    close(saved_stdout);
    avr->frequency = F_CPU;
    avr->vcc = avr->avcc = avr->aref = AVCC_MV;
    avr->sleep = on_sleep;
    avr->log = 0;

    uint32_t flags = 0;
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            on_uart_byte, NULL);
    uart_in_irq = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON),
                            on_uart_xon, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF),
                            on_uart_xoff, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_OUT_TRIGGER),
                            on_adc_trigger, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), IOPORT_IRQ_PIN7),
                            on_tick_pin, NULL);
    /* PE4/PE5 are also INT4/INT5. The firmware leaves those interrupts off, but simavr polls a
     * held-low level-triggered pin every few cycles unless told not to (a 3x slow-down). */
    avr_extint_set_strict_lvl_trig(avr, 4, 0);
    avr_extint_set_strict_lvl_trig(avr, 5, 0);
    cts_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('E'), IOPORT_IRQ_PIN4);
    strap_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('E'), IOPORT_IRQ_PIN5);
    drive_inputs();
}

int main(int argc, char **argv) {
    const char *paths[2];
    int npaths = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--no-flow-control")) flow_control = 0;
        else if (!strcmp(argv[i], "--stats") && i + 1 < argc) stats_path = argv[++i];
        else if (argv[i][0] == '-') usage();
        else if (npaths < 2) paths[npaths++] = argv[i];
        else usage();
    }
    if (npaths != 2) usage();
    load_trace(paths[0]);
    setup_board(paths[1]);
    master_fd = open_pty();
    printf("%s\n", ptsname(master_fd));
    fflush(stdout);

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGUSR1, &sa, NULL);
    sigaction(SIGUSR2, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    /* The board powers up when the port is first opened, so that no frames pile up in the
     * terminal before a reader is there (its first frames would arrive in a burst). */
    for (;;) {
        struct pollfd pfd = {.fd = master_fd, .events = POLLIN};
        if (want_stop) return 0;
        if (poll(&pfd, 1, 5) >= 0 && !(pfd.revents & POLLHUP)) break;
    }

    const uint64_t start = now_ns();
    const uint64_t cycle0 = avr->cycle;
    uint64_t next_service = 0, next_stats = 1;
    /* CRACKBOT_EMU_PROFILE=FILE: cycles spent at each program address, for finding hot code. */
    const char *profile_path = getenv("CRACKBOT_EMU_PROFILE");
    uint64_t *profile = profile_path ? calloc(0x20000, sizeof *profile) : NULL;
    while (!want_stop) {
        uint32_t pc = avr->pc;
        uint64_t before = avr->cycle;
        uint8_t depth = avr->interrupts.running_ptr;
        uint8_t vector = depth ? avr->interrupts.running[depth - 1]->vector : 0;
        step_slept = 0;
        int state = avr_run(avr);
        uint64_t stepped = avr->cycle - before;
        if (stepped > step_slept) {
            uint64_t spent = stepped - step_slept;
            st.awake_cycles += spent;
            st.vector_cycles[vector & 63] += spent;
            if (profile) profile[(pc >> 1) & 0x1FFFF] += spent;
        }
        if (state == cpu_Done || state == cpu_Crashed) {
            fprintf(stderr, "crackbot-mega2560-emulator: the firmware stopped (state %d)\n", state);
            break;
        }
        uint64_t emulated = avr->cycle - cycle0;
        if (emulated < next_service) continue;
        /* Once per emulated millisecond: reset/stop requests, the bridge, pacing. */
        next_service = emulated + F_CPU / 1000;
        if (want_reset) {
            want_reset = 0;
            power_on_reset();
        }
        bridge_service();
        uint64_t emulated_ns = emulated * 1000000000ULL / F_CPU;
        uint64_t wall_ns = now_ns() - start;
        if (emulated_ns > wall_ns + 500000ULL) {
            struct timespec ts = {.tv_sec = 0, .tv_nsec = (long)(emulated_ns - wall_ns)};
            nanosleep(&ts, NULL);
        }
        if (stats_path && emulated >= next_stats * F_CPU) {
            next_stats++;
            save_stats();
        }
    }
    if (profile) {
        FILE *f = fopen(profile_path, "w");
        for (uint32_t i = 0; f && i < 0x20000; i++)
            if (profile[i]) fprintf(f, "%x %llu\n", i << 1, (unsigned long long)profile[i]);
        if (f) fclose(f);
    }
    save_stats();
    write_stats(stderr);
    avr_terminate(avr);
    return 0;
}
