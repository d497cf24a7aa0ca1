/*
 * flexdigit-stream protocol, version 2: one checksummed ASCII line per sample (plain C, no Arduino dependency,
 * so the host test suite compiles it with gcc and decodes its output with flexdigit's own decoder).
 *
 *   $V2,<seq>,<t_us>,<G>,<g1>,...,<gG>[,<pot>[,<rot>]]*<CRC>\r\n   version 2: any digit's G = 1..8 gauges
 *   $<seq>,<t_us>,<g1>,<g2>,<g3>[,<pot>]*<CRC>\r\n           version 1: three gauges (still read by the host)
 *
 *   V2       the literal tag of a version-2 line
 *   seq      0..65535, +1 per line, wraps to 0: a gap tells the host a line was lost
 *   t_us     0..4294967295, micros() when the sample was taken
 *   G        how many gauges follow, 1..8
 *   g1..gG   the gauges (base to tip), signed ADC counts
 *   pot      optional servo potentiometer, signed ADC counts (the reference board firmware sends its command here)
 *   rot      optional, only after pot: the board's rotation estimate of these gauges, micro-degrees (a board that
 *            closes the loop itself: firmware/flexdigit_board.c); a line without it still reads
 *   CRC      4 hex digits, CRC-16/XMODEM (poly 0x1021, init 0) of the bytes between '$' and '*'
 *
 * Lines starting with '#' are information (the banner) and never data.
 */
#ifndef FLEXDIGIT_STREAM_H
#define FLEXDIGIT_STREAM_H

#include <stdint.h>
#include <stdio.h>

#define FLEXDIGIT_STREAM_VERSION 2
#define FLEXDIGIT_STREAM_MAX_GAUGES 8
/* the longest line: "$V2,65535,4294967295,8," + 10 x "-2147483648," + "*FFFF\r\n" + NUL = 150 bytes */
#define FLEXDIGIT_STREAM_LINE_MAX 152

static inline uint16_t flexdigit_crc16_xmodem(const char *data, int length) {
  uint16_t crc = 0;
  for (int i = 0; i < length; i++) {
    crc ^= (uint16_t)((uint8_t)data[i]) << 8;
    for (int bit = 0; bit < 8; bit++) {
      crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021) : (uint16_t)(crc << 1);
    }
  }
  return crc;
}

/* Format one version-1 sample (three gauges) into out (at least FLEXDIGIT_STREAM_LINE_MAX bytes); has_pot = 0 leaves the pot out.
 * Returns the line's length in bytes (without the terminating NUL). */
static inline int flexdigit_format_line(char *out, uint16_t seq, uint32_t t_us, int32_t g1, int32_t g2, int32_t g3,
                                        int has_pot, int32_t pot) {
  int n = snprintf(out, FLEXDIGIT_STREAM_LINE_MAX, "$%u,%lu,%ld,%ld,%ld", (unsigned)seq, (unsigned long)t_us,
                   (long)g1, (long)g2, (long)g3);
  if (has_pot) {
    n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), ",%ld", (long)pot);
  }
  uint16_t crc = flexdigit_crc16_xmodem(out + 1, n - 1); /* the bytes between '$' and '*' */
  n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), "*%04X\r\n", (unsigned)crc);
  return n;
}

/* Format one version-2 sample of count (1..8) gauges g[0..count-1] into out (at least FLEXDIGIT_STREAM_LINE_MAX
 * bytes); has_pot = 0 leaves the pot out. Returns the line's length in bytes (without the NUL), 0 for a bad count. */
static inline int flexdigit_format_line_v2(char *out, uint16_t seq, uint32_t t_us, const int32_t *g, int count,
                                           int has_pot, int32_t pot) {
  if (count < 1 || count > FLEXDIGIT_STREAM_MAX_GAUGES) {
    return 0;
  }
  int n = snprintf(out, FLEXDIGIT_STREAM_LINE_MAX, "$V2,%u,%lu,%d", (unsigned)seq, (unsigned long)t_us, count);
  for (int i = 0; i < count; i++) {
    n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), ",%ld", (long)g[i]);
  }
  if (has_pot) {
    n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), ",%ld", (long)pot);
  }
  uint16_t crc = flexdigit_crc16_xmodem(out + 1, n - 1); /* the bytes between '$' and '*', the tag included */
  n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), "*%04X\r\n", (unsigned)crc);
  return n;
}

/* Format one version-2 sample with the pot field (the board firmware's command) and the rotation estimate rot_udeg
 * (micro-degrees) after it. Returns the line's length in bytes (without the NUL), 0 for a bad count. */
static inline int flexdigit_format_line_v2_rotation(char *out, uint16_t seq, uint32_t t_us, const int32_t *g,
                                                    int count, int32_t pot, int32_t rot_udeg) {
  if (count < 1 || count > FLEXDIGIT_STREAM_MAX_GAUGES) {
    return 0;
  }
  int n = snprintf(out, FLEXDIGIT_STREAM_LINE_MAX, "$V2,%u,%lu,%d", (unsigned)seq, (unsigned long)t_us, count);
  for (int i = 0; i < count; i++) {
    n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), ",%ld", (long)g[i]);
  }
  n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), ",%ld,%ld", (long)pot, (long)rot_udeg);
  uint16_t crc = flexdigit_crc16_xmodem(out + 1, n - 1); /* the bytes between '$' and '*', the tag included */
  n += snprintf(out + n, (size_t)(FLEXDIGIT_STREAM_LINE_MAX - n), "*%04X\r\n", (unsigned)crc);
  return n;
}

#endif
