/*
 * flexdigit_hil: the firmware image on simavr's ATmega328P, driven in simulated time by flexdigit's `hil://`
 * backend over this process's stdin/stdout (issue 25, hardware in the loop).
 *
 *   flexdigit_hil FIRMWARE.elf [--pty]
 *
 * With --pty the firmware's UART is a pseudo-terminal: the first line on stdout is `T <path>`, the serial port
 * the host opens (as it opens an Uno's /dev/ttyACM0, in raw mode); the UART's bytes then travel over it, not in
 * the replies. Time stays the host's to give: the reply to R says how many bytes the AVR sent in that step and
 * they are on the pty before the reply is written; `U <n>` says the host has written n bytes to the pty, which
 * the harness reads before it answers the next request (a pty's two sides are joined asynchronously by the
 * kernel: counting the bytes, not polling for them, keeps a run exactly repeatable).
 *
 * One request a line on stdin, one reply a line on stdout:
 *
 *   V <v0> .. <vk>              the voltages on ADC0..ADCk, k < 8 (tenths of a millivolt, 0..50000), held until the
 *                               next V; pins not given hold 2.5 V (the firmware reads its G gauges on ADC0..ADC(G-1))
 *   U <hex>                     bytes for the firmware's UART receiver (delivered one per BYTE_US of AVR time);
 *                               with --pty, U <n>: n bytes the host wrote to the pty, for the receiver
 *   R <us>                      run the AVR for <us> microseconds of simulated time, then reply
 *       P <t_us> <pulse_cycles> <pulses> <exec_last> <exec_max> <execs> <pin_cycles> <idle_cycles> <hex of the
 *         UART's output>
 *         (with --pty: the number of bytes the UART sent to the pty in this step instead of their hex)
 *         pulse_cycles: width of the servo pulse begun last on PB1 (OC1A), CPU cycles (16 MHz): OCR1A as latched
 *           at the pulse's start (BOTTOM), which is what the hardware does. simavr 1.6 keeps the pin's waveform
 *           at the OCR1A it had when the timer was configured, so pin_cycles (the width seen on the pin) is
 *           reported beside it but not used.
 *         pulses: pulses begun so far; exec_*: width of the high pulses on PD7 (the control update), cycles
 *         idle_cycles: cycles the CPU has slept so far (the firmware sleeps, SLEEP_MODE_IDLE, whenever it has
 *           nothing to do: no interrupt, no control period, no host line due): what is left of it for more work
 *   Q                           quit
 *
 * The AVR's clock is its own: nothing here depends on the wall clock, so a run repeats exactly.
 */
#define _XOPEN_SOURCE 600 /* posix_openpt, grantpt, unlockpt, ptsname */
#define _DEFAULT_SOURCE     /* cfmakeraw */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include <simavr/avr_adc.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>

#define FREQUENCY 16000000UL
#define BYTE_US 50 /* one received byte each 50 us: below the 40 us of a byte at 250000 baud, and never faster */
#define OUT_MAX 65536
#define OCR1AL_ADDR 0x88    /* OCR1A in the ATmega328P's data space */
#define TIMER1_PRESCALE 8UL /* the firmware's Timer1 clock: 0.5 us a tick */
/* simavr converts an ADC input as vin x 1023 / AVcc (avr_adc.c), the ATmega328P as vin x 1024 / AVcc (datasheet
   24.7): its AVcc is set to 5 V x 1023/1024 so the emulated ADC's steps fall where the chip's do (within 0.004 of
   a step over the range), and the inputs are given in tenths of a millivolt (1/50 of a step), not millivolts (1/5):
   the board's rest reading, which it tares its map on, then quantises as a real Uno's would */
#define VOLT_UNITS_PER_V 10000L
#define AVCC_UNITS 49951U /* 5 V x 1023 / 1024 in tenths of a millivolt */
#define ADC_PINS 8          /* ADC0..ADC7 (the Uno's DIP package brings out ADC0..ADC5) */

static avr_t *avr;
static unsigned char out_buf[OUT_MAX];
static size_t out_len;
static unsigned char in_buf[4096];
static size_t in_head, in_len;
static avr_cycle_count_t pulse_rise, exec_rise;
static unsigned long pulse_cycles, pulse_latched, pulses, exec_last, exec_max, execs;
static unsigned long long idle_cycles;
static FILE *reply;
static int pty_master = -1, pty_slave = -1;
#define PTY_TIMEOUT_MS 5000 /* the host's bytes are on their way once it says so: 5 s is a host gone */

/* A pty in raw mode (no echo, no line editing, no CR/LF translation: a serial port's bytes as they are); the
   harness keeps its slave side open too, so the host may close and reopen it without a hang-up. */
static const char *open_pty(void)
{
    struct termios raw;
    const char *path;
    pty_master = posix_openpt(O_RDWR | O_NOCTTY);
    if (pty_master < 0 || grantpt(pty_master) != 0 || unlockpt(pty_master) != 0 || !(path = ptsname(pty_master))) {
        return NULL;
    }
    pty_slave = open(path, O_RDWR | O_NOCTTY);
    if (pty_slave < 0 || tcgetattr(pty_slave, &raw) != 0) {
        return NULL;
    }
    cfmakeraw(&raw);
    if (tcsetattr(pty_slave, TCSANOW, &raw) != 0) {
        return NULL;
    }
    return path;
}

/* Read exactly n bytes the host wrote to the pty into the receiver's queue; 0 on success. */
static int read_pty(size_t n)
{
    while (n > 0) {
        struct pollfd fd = {pty_master, POLLIN, 0};
        unsigned char chunk[256];
        ssize_t got;
        size_t want = n < sizeof(chunk) ? n : sizeof(chunk);
        if (poll(&fd, 1, PTY_TIMEOUT_MS) != 1) {
            return -1;
        }
        got = read(pty_master, chunk, want);
        if (got <= 0) {
            if (got < 0 && errno == EINTR) continue;
            return -1;
        }
        if (in_len == 0) in_head = 0;
        if (in_head + in_len + (size_t)got > sizeof(in_buf)) {
            return -1;
        }
        memcpy(in_buf + in_head + in_len, chunk, (size_t)got);
        in_len += (size_t)got;
        n -= (size_t)got;
    }
    return 0;
}

/* Write the UART's bytes of this step to the pty; 0 on success. */
static int write_pty(void)
{
    size_t done = 0;
    while (done < out_len) {
        ssize_t put = write(pty_master, out_buf + done, out_len - done);
        if (put < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        done += (size_t)put;
    }
    return 0;
}

static void uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (out_len < OUT_MAX) {
        out_buf[out_len++] = (unsigned char)value;
    }
}

static void servo_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value) {
        /* the pulse starts at BOTTOM, where the hardware latches the double-buffered OCR1A: the width this period */
        unsigned ocr = (unsigned)avr->data[OCR1AL_ADDR] | ((unsigned)avr->data[OCR1AL_ADDR + 1] << 8);
        pulse_latched = (unsigned long)(ocr + 1U) * TIMER1_PRESCALE;
        pulse_rise = avr->cycle;
        pulses++;
    } else if (pulse_rise) {
        pulse_cycles = (unsigned long)(avr->cycle - pulse_rise);
    }
}

static void exec_pin(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value) {
        exec_rise = avr->cycle;
    } else if (exec_rise) {
        exec_last = (unsigned long)(avr->cycle - exec_rise);
        if (exec_last > exec_max) {
            exec_max = exec_last;
        }
        execs++;
    }
}

/* The CPU sleeps (SLEEP): simavr skips to its next cycle timer (a peripheral's event, or one of run_us's below)
   and calls this with the cycles skipped; it then adds 1 + how_long to the clock. simavr's own callback usleeps
   that long (wall-clock pacing): here the time is only counted, so a run stays in simulated time. */
static void sleep_counted(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    idle_cycles += 1ULL + how_long;
}

/* A cycle timer that does nothing: it bounds a sleep, so the CPU wakes no later than run_us's end or its next
   received byte (both deadlines the harness keeps between avr_run calls). */
static int end_deadline, byte_deadline; /* the two deadlines' params: simavr keeps one timer per (callback, param) */
static avr_cycle_count_t deadline(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)when;
    (void)param;
    return 0;
}

static int hexval(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static void run_us(unsigned long us)
{
    avr_cycle_count_t end = avr->cycle + (avr_cycle_count_t)us * (FREQUENCY / 1000000UL);
    avr_cycle_count_t next_byte = avr->cycle;
    avr_irq_t *rx = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_cycle_timer_register(avr, end - avr->cycle, deadline, &end_deadline);
    while (avr->cycle < end) {
        if (in_len > 0 && avr->cycle >= next_byte) {
            avr_raise_irq(rx, in_buf[in_head]);
            in_head++;
            in_len--;
            next_byte = avr->cycle + BYTE_US * (FREQUENCY / 1000000UL);
            if (in_len > 0 && next_byte < end) {
                avr_cycle_timer_register(avr, next_byte - avr->cycle, deadline, &byte_deadline);
            }
        }
        int state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed) {
            fprintf(stderr, "flexdigit_hil: the AVR stopped (state %d)\n", state);
            exit(3);
        }
    }
}

int main(int argc, char **argv)
{
    elf_firmware_t firmware;
    char line[8192];
    int i;
    uint32_t flags = 0;
    int use_pty = argc == 3 && strcmp(argv[2], "--pty") == 0;
    if (argc != 2 && !use_pty) {
        fprintf(stderr, "usage: flexdigit_hil FIRMWARE.elf [--pty]\n");
        return 2;
    }
    /* replies on the original stdout; anything simavr prints goes to stderr */
    reply = fdopen(dup(1), "w");
    dup2(2, 1);
    memset(&firmware, 0, sizeof(firmware));
    if (elf_read_firmware(argv[1], &firmware) != 0) {
        fprintf(stderr, "flexdigit_hil: cannot read %s\n", argv[1]);
        return 2;
    }
    avr = avr_make_mcu_by_name("atmega328p");
    if (!avr) {
        fprintf(stderr, "flexdigit_hil: simavr has no atmega328p\n");
        return 2;
    }
    avr_init(avr);
    avr_load_firmware(avr, &firmware);
    avr->frequency = FREQUENCY;
    avr->vcc = avr->aref = 5000;
    avr->avcc = AVCC_UNITS;
    avr->sleep = sleep_counted;
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), uart_out, NULL);
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)AVR_UART_FLAG_STDIO;
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 1), servo_pin, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 7), exec_pin, NULL);
    for (i = 0; i < ADC_PINS; i++) {
        avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + i), (uint32_t)(VOLT_UNITS_PER_V * 5 / 2));
    }
    if (use_pty) {
        const char *path = open_pty();
        if (!path) {
            fprintf(stderr, "flexdigit_hil: cannot open a pty (%s)\n", strerror(errno));
            return 2;
        }
        fprintf(reply, "T %s\n", path);
        fflush(reply);
    }
    while (fgets(line, sizeof(line), stdin)) {
        if (line[0] == 'V') {
            char *p = line + 1;
            for (i = 0; i < ADC_PINS; i++) {
                char *end;
                long top = 5L * VOLT_UNITS_PER_V;
                long v = strtol(p, &end, 10);
                if (end == p) {
                    break; /* the pins not given keep their voltage */
                }
                p = end;
                v = v < 0 ? 0 : (v > top ? top : v);
                avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + i), (uint32_t)v);
            }
        } else if (line[0] == 'U' && use_pty) {
            if (read_pty(strtoul(line + 1, NULL, 10)) != 0) {
                fprintf(stderr, "flexdigit_hil: the host's bytes did not arrive on the pty\n");
                return 3;
            }
        } else if (line[0] == 'U') {
            char *p = line + 1;
            while (*p == ' ') p++;
            if (in_len == 0) in_head = 0;
            while (hexval(p[0]) >= 0 && hexval(p[1]) >= 0 && in_head + in_len < sizeof(in_buf)) {
                in_buf[in_head + in_len] = (unsigned char)(hexval(p[0]) * 16 + hexval(p[1]));
                in_len++;
                p += 2;
            }
        } else if (line[0] == 'R') {
            unsigned long us = strtoul(line + 1, NULL, 10);
            size_t k;
            run_us(us);
            fprintf(reply, "P %llu %lu %lu %lu %lu %lu %lu %llu ",
                    (unsigned long long)(avr->cycle / (FREQUENCY / 1000000UL)), pulse_latched, pulses, exec_last,
                    exec_max, execs, pulse_cycles, idle_cycles);
            if (use_pty) {
                if (write_pty() != 0) {
                    fprintf(stderr, "flexdigit_hil: cannot write to the pty (%s)\n", strerror(errno));
                    return 3;
                }
                fprintf(reply, "%lu", (unsigned long)out_len);
            } else {
                for (k = 0; k < out_len; k++) {
                    fprintf(reply, "%02x", out_buf[k]);
                }
            }
            fprintf(reply, "\n");
            fflush(reply);
            out_len = 0;
        } else if (line[0] == 'Q') {
            break;
        }
    }
    return 0;
}
