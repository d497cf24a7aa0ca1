/*
 * flexdigit-stream: the strain-gauge channels (and the servo pot) of a flexible digit, read by an ADS1115 on an
 * Arduino-class board and sent to flexdigit over USB serial (protocol version 2), as `stream://PORT` reads them.
 * GAUGE_COUNT below is the digit's gauge count (its params file's gauge_positions_m; the thesis rig's 3); the host
 * opened with that digit (--params FILE) refuses a board sending another count.
 *
 * Wiring (replaces the thesis's PCI-DAS1602/16, table 2.2): the three amplified half-bridge outputs on ADS1115
 * inputs A0, A1, A2 (gauges 1, 2, 3 from the base), the servo potentiometer wiper on A3 (optional), ADS1115 on I2C
 * (SDA/SCL), ADDR to GND (0x48). The amplifier outputs must stay within the ADC's range (here +-4.096 V, and never
 * beyond the ADS1115's supply).
 *
 * Library: "Adafruit ADS1X15" (Arduino library manager). Board: any Arduino-class board with I2C and USB serial.
 *
 * Host side: flexdigit run --backend "serial:///dev/ttyUSB0?daq=stream:///dev/ttyACM0&daq.scale=0.000125"
 * (scale = volts per count: 4.096 V / 32768 = 0.000125 at GAIN_ONE). The protocol is in flexdigit_stream.h.
 *
 * Rate: single-shot conversions at 860 SPS take ~1.2 ms each, so four channels fit in 5 ms; 100 lines/s leaves
 * the 20 ms control loop five fresh samples per period. At 115200 baud a line (< 60 bytes) takes ~5 ms.
 *
 * More than three gauges: one ADS1115 has four inputs; wire a second at ADDR = VDD (0x49), read its inputs in
 * read_gauges() for gauges 4.. and set GAUGE_COUNT (up to 8; the pot then moves to the second chip's last input).
 *
 * HX711 instead (one per gauge, 24-bit, 10 or 80 SPS): read the chips in read_gauges() below, send
 * their counts unchanged, and on the host set daq.bits=24, daq.scale to your bridge's volts per count and
 * daq.timeout above the conversion period (0.3 s at 10 SPS).
 */
#include <Adafruit_ADS1X15.h>

#include "flexdigit_stream.h"

static const unsigned long BAUD = 115200;
static const unsigned long PERIOD_US = 10000;  // 100 lines per second
static const bool SEND_POT = true;             // false if the pot is not wired (the host reads NaN)
#define GAUGE_COUNT 3                          // the digit's gauges, 1..FLEXDIGIT_STREAM_MAX_GAUGES (ADS1115 A0..)

Adafruit_ADS1115 ads;
static uint16_t seq = 0;
static uint32_t next_us = 0;  // uint32_t, not unsigned long: wraps with micros() where long has 64 bits

static void read_gauges(int32_t *g, int32_t *pot) {
  for (int i = 0; i < GAUGE_COUNT; i++) {  // one ADS1115: gauges on A0..A2 and the pot on A3 (see above for more)
    g[i] = ads.readADC_SingleEnded(i);
  }
  *pot = SEND_POT ? ads.readADC_SingleEnded(GAUGE_COUNT) : 0;
}

void setup() {
  Serial.begin(BAUD);
  while (!Serial) {
  }  // boards with native USB: wait for the host to open the port
  if (!ads.begin()) {
    Serial.println("# flexdigit-stream error: no ADS1115 at 0x48");
    while (true) {
    }  // send no data: the host reports a silent stream and stays in its safe state
  }
  ads.setGain(GAIN_ONE);                  // +-4.096 V: 0.000125 V per count
  ads.setDataRate(RATE_ADS1115_860SPS);
  Serial.print("# flexdigit-stream ");
  Serial.print(FLEXDIGIT_STREAM_VERSION);
  Serial.print(" adc=ADS1115 v_per_count=0.000125 rate_hz=100 gauges=");
  Serial.println(GAUGE_COUNT);
  next_us = (uint32_t)micros();
}

void loop() {
  if ((int32_t)((uint32_t)micros() - next_us) < 0) {  // wrap-safe: micros() wraps every 71.6 min
    return;
  }
  next_us += PERIOD_US;
  int32_t g[GAUGE_COUNT];
  int32_t pot;
  uint32_t t_us = (uint32_t)micros();
  read_gauges(g, &pot);
  char line[FLEXDIGIT_STREAM_LINE_MAX];
  int n = flexdigit_format_line_v2(line, seq++, t_us, g, GAUGE_COUNT, SEND_POT, pot);
  Serial.write((const uint8_t *)line, n);
}
