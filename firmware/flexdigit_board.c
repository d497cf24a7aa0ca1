/*
 * flexdigit-board: the flexible digit's controller on an ATmega328P (Arduino Uno), avr-libc only (issue 25).
 *
 * - Timer2 interrupt at SAMPLE_HZ (1 kHz): starts the ADC on channel 0; the ADC interrupt reads gauges 1..3
 *   (ADC0..ADC2, each behind a +2.5 V level shift: 0 V of gauge = count 512) and the servo pot (ADC3), one after
 *   the other; the sample counts once its gauges are in (~0.32 ms after the tick).
 * - Every FD_CTRL_PERIOD_US the main loop runs the exported controller (ctrl.c, from
 *   `flexdigit export controller`) on the gauges' rotation estimate of that tick and sets the servo pulse (its
 *   width latched by Timer1 at the pulse's start, 1 ms after the tick: the update, <= 0.55 ms, is done by then).
 * - Timer1, fast PWM (mode 14), 50 Hz, 0.5 us per tick: the servo pulse on OC1A (PB1, Uno pin 9), 1..2 ms for
 *   commands 0..254 (the serial servo board's range); 2000 ticks over that range.
 * - USART0 at BAUD: samples in flexdigit's stream protocol (`$seq,t_us,g1,g2,g3,command*CRC`: the ADC counts
 *   the period's update used, signed about the 2.5 V midpoint, and the command it applied), information lines `# ...`.
 *   From the host, one command a line: S<millideg> setpoint, M<0|1|2> mode (0 safe, 1 host commands,
 *   2 loop on the board), C<0..254> command (mode 1), F<0|1> safe action (0 relax, 1 hold), W heartbeat.
 * - Safety (checked every control period): host silent for HOST_TIMEOUT_MS (modes 1, 2), a gauge at an ADC rail
 *   (a wire off), the rotation estimate beyond ROTATION_LIMIT_DEG, a command out of range (host or controller):
 *   safe state (relax to the equilibrium command, or hold) and `# fault <code> <name>`; cleared by an M line.
 * - PD7 (Uno pin 7) is high while the control update runs: its width is the update's execution time (a pin of
 *   another port than the servo's, so its writes never touch OC1A's port).
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "ctrl.h"
#include "flexdigit_stream.h"

#ifndef F_CPU
#error "F_CPU must be defined (16000000UL on an Uno)"
#endif
#define SAMPLE_HZ 1000UL
#define BAUD 250000UL /* exact at 16 MHz with U2X (UBRR 7); the Uno's USB bridge carries it */
#define HOST_TIMEOUT_MS 500U
#define ROTATION_LIMIT_DEG 100.0f
#define VOLTS_PER_COUNT (5.0f / 1024.0f)
#define MID_COUNT 512
#define REST_SAMPLES 8U /* the rest reading: a mean over up to 8 control periods */
#define PULSE_MIN_TICKS 2000U /* 1 ms at 0.5 us a tick */
#define PULSE_SPAN_TICKS 2000U
#define SERVO_TOP 39999U /* 20 ms */
#define CONTROL_DIV ((uint16_t)(FD_CTRL_PERIOD_US / (1000000UL / SAMPLE_HZ)))
#define STREAM_MIN_US 4000UL /* at most 250 lines a second: one line is ~40 bytes at 25 kB/s */
#define STREAM_DIV ((uint16_t)((FD_CTRL_PERIOD_US >= STREAM_MIN_US) ? 1 : (STREAM_MIN_US / FD_CTRL_PERIOD_US)))

#if !FD_CTRL_HAS_MEASURE
#error "export the controller with its rotation map (flexdigit export controller without --no-rotation-map)"
#endif
#if FD_CTRL_PERIOD_US > 20000UL || 20000UL % FD_CTRL_PERIOD_US != 0
#error "the controller's period must divide the servo's 20 ms frame (20, 10, 5, 4, 2 or 1 ms)"
#endif
#if FD_CTRL_PERIOD_US % (1000000UL / SAMPLE_HZ) != 0
#error "the controller's period must be a whole number of ADC samples (1 ms)"
#endif

enum { MODE_SAFE = 0, MODE_HOST = 1, MODE_BOARD = 2 };
enum { FAULT_NONE = 0, FAULT_HOST_TIMEOUT, FAULT_ADC_RAIL, FAULT_ROTATION, FAULT_COMMAND, FAULT_CONTROLLER };
static const char *const FAULT_NAMES[] = {"none", "host_timeout", "adc_rail", "rotation_bound", "command_range",
                                          "controller"};

/* -- sampling (interrupts) -------------------------------------------------------------------------------------- */
static volatile uint16_t adc_work[4];
static volatile uint16_t adc_last[4];
static volatile uint8_t adc_channel;
static volatile uint16_t ticks;     /* samples since the last control period */
static volatile uint32_t time_ms;   /* board clock, ms */
static volatile uint16_t host_idle; /* ms since the last line from the host */

ISR(TIMER2_COMPA_vect)
{
    if (!(TCCR1B & _BV(CS11))) {
        TCCR1B |= _BV(CS11); /* the servo's 50 Hz frame starts here: pulses at 1 ms + k x 20 ms */
    }
    time_ms++;
    if (host_idle < 0xFFFFU) {
        host_idle++;
    }
    adc_channel = 0;
    ADMUX = (uint8_t)(_BV(REFS0) | 0); /* AVcc reference, channel 0 */
    ADCSRA |= _BV(ADSC);
}

ISR(ADC_vect)
{
    uint8_t ch = adc_channel;
    adc_work[ch] = ADC;
    ch++;
    if (ch == 3) {
        /* the gauges of this tick are in: the control period may use them now (~0.32 ms after the tick), not
           the previous tick's (1 ms older); the pot's conversion follows while the update runs */
        uint8_t i;
        for (i = 0; i < 3; i++) {
            adc_last[i] = adc_work[i];
        }
        ticks++;
    } else if (ch == 4) {
        adc_last[3] = adc_work[3];
    }
    if (ch < 4) {
        adc_channel = ch;
        ADMUX = (uint8_t)(_BV(REFS0) | ch);
        ADCSRA |= _BV(ADSC);
    }
}

/* -- serial ------------------------------------------------------------------------------------------------------ */
#define TX_SIZE 256U
static volatile uint8_t tx_buf[TX_SIZE];
static volatile uint8_t tx_head, tx_tail;
#define RX_SIZE 64U
static volatile uint8_t rx_buf[RX_SIZE];
static volatile uint8_t rx_head, rx_tail;
static char rx_line[24];
static uint8_t rx_len;

ISR(USART_UDRE_vect)
{
    if (tx_head == tx_tail) {
        UCSR0B &= (uint8_t)~_BV(UDRIE0);
    } else {
        UDR0 = tx_buf[tx_tail];
        tx_tail = (uint8_t)(tx_tail + 1U);
    }
}

ISR(USART_RX_vect)
{
    uint8_t next = (uint8_t)((rx_head + 1U) % RX_SIZE);
    uint8_t c = UDR0;
    if (next != rx_tail) { /* full: the byte is lost (the host's next line resynchronises) */
        rx_buf[rx_head] = c;
        rx_head = next;
    }
}

static void send(const char *text, int length)
{
    int i;
    for (i = 0; i < length; i++) {
        uint8_t next = (uint8_t)(tx_head + 1U);
        if (next == tx_tail) {
            return; /* full: drop the rest of this line (the host sees a garbled line and counts it) */
        }
        tx_buf[tx_head] = (uint8_t)text[i];
        tx_head = next;
    }
    UCSR0B |= _BV(UDRIE0);
}

static void send_text(const char *text)
{
    int n = 0;
    while (text[n] != '\0') {
        n++;
    }
    send(text, n);
}

/* -- the servo ---------------------------------------------------------------------------------------------------- */
static int16_t command_now = FD_CTRL_COMMAND_EQ;

static void set_command(int16_t command)
{
    uint32_t ticks_pulse = PULSE_MIN_TICKS + ((uint32_t)command * PULSE_SPAN_TICKS + 127U) / 254U;
    command_now = command;
    OCR1A = (uint16_t)(ticks_pulse - 1U);
}

/* -- state -------------------------------------------------------------------------------------------------------- */
static fd_ctrl_t ctrl;
static uint8_t mode = MODE_SAFE;
static uint8_t fault = FAULT_NONE;
static uint8_t safe_hold = 0;
static float setpoint_deg = 0.0f;
static uint16_t sample_raw[3] = {MID_COUNT, MID_COUNT, MID_COUNT}; /* the ADC counts the last period used */
static uint32_t sample_ms;
static float rest_v[3];
static uint8_t rest_n = 0;
static float tare_deg = 0.0f; /* the rotation the map reads at rest, subtracted while the loop runs */

static void enter_safe(uint8_t code)
{
    char line[40];
    if (!safe_hold) {
        set_command(FD_CTRL_COMMAND_EQ);
    }
    if (code != FAULT_NONE && fault == FAULT_NONE) {
        fault = code;
        snprintf(line, sizeof(line), "# fault %u %s\r\n", (unsigned)code, FAULT_NAMES[code]);
        send_text(line);
    }
    mode = MODE_SAFE;
}

static void handle_line(const char *line)
{
    long value = strtol(line + 1, NULL, 10);
    char out[32];
    switch (line[0]) {
    case 'S':
        setpoint_deg = (float)value / 1000.0f;
        break;
    case 'M':
        if (value < MODE_SAFE || value > MODE_BOARD) {
            return;
        }
        fault = FAULT_NONE;
        if (value == MODE_BOARD) {
            float rest[3];
            uint8_t i;
            for (i = 0; i < 3; i++) {
                rest[i] = rest_v[i];
            }
            tare_deg = fd_ctrl_measure(rest);
            fd_ctrl_reset(&ctrl, (float)command_now); /* bumpless: from the command in force */
            snprintf(out, sizeof(out), "# tare %ld\r\n", (long)(tare_deg * 1.0e6f)); /* micro-degrees */
            send_text(out);
        }
        if (value == MODE_SAFE) {
            enter_safe(FAULT_NONE);
        }
        mode = (uint8_t)value;
        snprintf(out, sizeof(out), "# mode %u\r\n", (unsigned)mode);
        send_text(out);
        break;
    case 'C':
        if (value < FD_CTRL_COMMAND_MIN || value > FD_CTRL_COMMAND_MAX) {
            enter_safe(FAULT_COMMAND);
        } else if (mode == MODE_HOST) {
            set_command((int16_t)value);
        }
        break;
    case 'F':
        safe_hold = (uint8_t)(value != 0);
        break;
    default: /* 'W' and anything else: a heartbeat */
        break;
    }
}

static void control_period(void)
{
    uint16_t raw[4];
    float g[3];
    float rotation;
    uint8_t i;
    int16_t command = command_now;
    cli();
    for (i = 0; i < 4; i++) {
        raw[i] = adc_last[i];
    }
    sample_ms = time_ms;
    sei();
    for (i = 0; i < 3; i++) {
        sample_raw[i] = raw[i]; /* what this period used: streamed, so the host sees the loop's own inputs */
    }
    for (i = 0; i < 3; i++) {
        /* + half a count: the ADC truncates, so a count stands for the middle of its 4.9 mV step */
        g[i] = ((float)((int16_t)raw[i] - MID_COUNT) + 0.5f) * VOLTS_PER_COUNT;
    }
    if (mode != MODE_BOARD) {
        /* the rest reading the loop is tared on when it starts (as the host's loop tares its map): the mean of
           the last readings, the first REST_SAMPLES of them equally weighted, then an exponential average */
        if (rest_n < REST_SAMPLES) {
            rest_n++;
        }
        for (i = 0; i < 3; i++) {
            rest_v[i] += (g[i] - rest_v[i]) / (float)rest_n;
        }
    }
    if (mode != MODE_SAFE) {
        for (i = 0; i < 3; i++) {
            if (raw[i] == 0U || raw[i] >= 1023U) {
                enter_safe(FAULT_ADC_RAIL);
            }
        }
        if (host_idle > HOST_TIMEOUT_MS) {
            enter_safe(FAULT_HOST_TIMEOUT);
        }
    }
    rotation = fd_ctrl_measure(g) - tare_deg;
    if (mode == MODE_BOARD) {
        int code;
        /* the rotation bound is on the loop's own estimate of the beam rotation (deg) */
        if (rotation > ROTATION_LIMIT_DEG || rotation < -ROTATION_LIMIT_DEG) {
            enter_safe(FAULT_ROTATION);
        } else {
            PORTD |= _BV(PORTD7);
            code = fd_ctrl_update(&ctrl, setpoint_deg * FD_CTRL_SETPOINT_SCALE, rotation, &command);
            PORTD &= (uint8_t)~_BV(PORTD7);
            if (code != FD_CTRL_OK) {
                enter_safe(FAULT_CONTROLLER);
            } else if (command < FD_CTRL_COMMAND_MIN || command > FD_CTRL_COMMAND_MAX) {
                enter_safe(FAULT_COMMAND);
            } else {
                set_command(command);
            }
        }
    }
}

static void stream_sample(uint16_t seq)
{
    char line[FLEXDIGIT_STREAM_LINE_MAX];
    int n = flexdigit_format_line(line, seq, sample_ms * 1000UL, (int32_t)sample_raw[0] - MID_COUNT,
                                  (int32_t)sample_raw[1] - MID_COUNT, (int32_t)sample_raw[2] - MID_COUNT, 1,
                                  command_now);
    send(line, n);
}

int main(void)
{
    uint16_t seq = 0, periods = 0;
    char banner[160];
    /* the servo pulse: Timer1 fast PWM, TOP = ICR1, prescaler 8 (0.5 us), OC1A non-inverting */
    DDRB |= _BV(DDB1);
    DDRD |= _BV(DDD7);
    ICR1 = SERVO_TOP;
    set_command(FD_CTRL_COMMAND_EQ);
    /* Timer1's clock starts at the first sample tick (below): each pulse then starts 1 ms after a control tick
       (every period divides 20 ms), so the command computed at a tick is latched by the pulse 1 ms later, not up
       to 20 ms later */
    TCCR1A = _BV(COM1A1) | _BV(WGM11);
    TCCR1B = _BV(WGM13) | _BV(WGM12);
    /* the ADC: AVcc reference, prescaler 128 (125 kHz, 104 us a conversion), interrupt on completion */
    ADMUX = _BV(REFS0);
    ADCSRA = _BV(ADEN) | _BV(ADIE) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0);
    /* the sample clock: Timer2 CTC, prescaler 64 (4 us), 250 counts = 1 ms */
    TCCR2A = _BV(WGM21);
    TCCR2B = _BV(CS22);
    OCR2A = (uint8_t)(F_CPU / 64UL / SAMPLE_HZ - 1UL);
    TIMSK2 = _BV(OCIE2A);
    /* the serial port: BAUD 8N1, double speed */
    UCSR0A = _BV(U2X0);
    UBRR0 = (uint16_t)(F_CPU / 8UL / BAUD - 1UL);
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    fd_ctrl_reset(&ctrl, (float)FD_CTRL_COMMAND_EQ);
    sei();
    snprintf(banner, sizeof(banner),
             "# flexdigit-stream %d adc=atmega328p v_per_count=0.0048828125 rate_hz=%lu board=flexdigit-board "
             "period_us=%lu fixed=%d\r\n",
             FLEXDIGIT_STREAM_VERSION, (unsigned long)(1000000UL / FD_CTRL_PERIOD_US / STREAM_DIV),
             (unsigned long)FD_CTRL_PERIOD_US, FD_CTRL_FIXED_POINT);
    send_text(banner);
    for (;;) {
        while (rx_tail != rx_head) {
            char c = (char)rx_buf[rx_tail];
            rx_tail = (uint8_t)((rx_tail + 1U) % RX_SIZE);
            if (c == '\n' || c == '\r') {
                if (rx_len > 0) {
                    rx_line[rx_len] = '\0';
                    rx_len = 0;
                    host_idle = 0;
                    handle_line(rx_line);
                }
            } else if (rx_len < sizeof(rx_line) - 1U) {
                rx_line[rx_len] = c;
                rx_len++;
            }
        }
        if (ticks >= CONTROL_DIV) {
            cli();
            ticks = (uint16_t)(ticks - CONTROL_DIV);
            sei();
            control_period();
            periods++;
            if (periods >= STREAM_DIV) {
                periods = 0;
                stream_sample(seq);
                seq++;
            }
        }
    }
}
