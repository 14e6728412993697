/*
 * skin_decoder.c: a decoder under test for the skinhil serial stream, in plain C (libc and
 * termios only), written from protocols/SPEC.md. Section numbers (§) below are the SPEC's.
 *
 * It reads the serial packet stream (§2-§4, §9) from a tty or from UDP datagrams (§10),
 * checks every CRC and sequence number, decodes every packet type, keeps the counters of
 * §6-§7, reads the SESSION record (§3.7: channel count, stimulus table; the SUITE and TASK
 * records that announce the suite case and its tasks' terms are checked and, with --stdin,
 * printed) and stops at the RUN_END record. It answers with DECISIONs (§3.5.1): a 5 ms bin holding more than
 * 3 x baseline + 5 events is an onset; each channel's events in the next 30 ms, scaled to
 * unit length, are compared with the average of earlier stimuli of each id (the nearest
 * wins); a ground-truth MARKER up to 50 ms before the onset then teaches that id (the rule
 * of examples/dut_threshold.py: it learns from the past only).
 *
 *   cc -O2 -o skin_decoder examples/skin_decoder.c -lm
 *   ./skin_decoder --tty /dev/pts/5 [--baud 921600]     # a serial port or a pty
 *   ./skin_decoder --udp 127.0.0.1:5005                   # bind here; answer the sender
 *   ./skin_decoder --stdin                                # conformance: bytes in, JSON out
 *
 * Live, it prints one JSON line at the end: its counters, the board's last STATUS, the
 * SESSION, the RUN_END reason and how many DECISIONs it sent. With --stdin it prints one
 * JSON line per decoded event and record, then the counters (protocols/conformance.json).
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define MAX_BODY 1024                /* §3: a body holds at most 1024 bytes */
#define MAX_WIRE 1032                /* §2: longest COBS-encoded packet, delimiter excluded */
#define CRC_RESIDUE 0x1D0F           /* §2: register over body || CRC of a good packet */
#define N_NARROW 338                 /* §3.1: narrow addresses 0..337 */
#define BITMAP_BYTES 43              /* §3.1 */
#define WIDE_INVALID 1048575u        /* §9: the all-ones wide address is invalid */
#define LATE_WINDOW 8                /* §6 rule 4: 1..8 behind is late */
#define EPOCH_GAP 32                 /* §6 rule 4: a gap of 32 or more loses the time base */
#define MAX_TIME_US (1ULL << 62)     /* §6 rule 5 */

enum { T_EVENTS, T_SYNC, T_STATUS, T_MARKER, T_COMMAND, T_ACK, T_WIDE, T_SESSION };
enum { K_SESSION, K_STIMULUS, K_RUN_END, K_SUITE, K_TASK };  /* §3.7: type 7 kinds */
static const int BODY_LEN[8] = {-1, 11, 60, 13, 9, 6, -1, -1};

/* §7: the counters a decoder keeps */
typedef struct {
    long long frames_ok, crc_errors, malformed, resyncs, bytes_discarded, seq_gaps,
        frames_lost, duplicates, late_frames, events_decoded, events_untimed, events_lost,
        events_lost_reported, syncs, command_seq_gaps, commands_lost;
} counters_t;

#define N_STATUS 13 /* §3.3: the u32 words after t_us, in wire order */
static const char *STATUS_NAMES[N_STATUS] = {
    "events_generated", "events_sent", "events_dropped", "events_queued", "late_ticks",
    "rx_errors", "dropped_fifo_full", "dropped_stopped", "dropped_link_down", "link_events",
    "dropped_shutdown", "markers_sent", "markers_dropped"};
enum { S_QUEUED = 3, S_DROPPED = 2, S_LINK = 9 };

typedef struct {
    counters_t c;
    unsigned char pending[2 * MAX_WIRE + 1];
    size_t npending;
    int have_seq, seq, have_cmd_seq, cmd_seq;           /* §6 rule 4 */
    int sync_valid, epoch, have_base, have_cand;        /* §6 rule 5 */
    long long base, cand, step_us;
    int have_status;                                    /* §7: status unwrapping */
    long long status_last[N_STATUS], l0, d0;
    long long status_value[N_STATUS], status_t_us;
    int status_running;
    /* SESSION (§3.7) */
    int have_session, run_ended, run_end_reason;
    unsigned n_channels, n_stimuli, table_digest;
} decoder_t;

static int json_out; /* --stdin: print every event and record */

/* ---- §2: CRC-16/GENIBUS register (before its final XOR) and COBS ---------------------- */
static unsigned crc16(const unsigned char *p, size_t n) {
    unsigned crc = 0xFFFF;
    for (size_t i = 0; i < n; i++) {
        crc ^= (unsigned)p[i] << 8;
        for (int b = 0; b < 8; b++) crc = (crc & 0x8000) ? ((crc << 1) ^ 0x1021) : (crc << 1);
        crc &= 0xFFFF;
    }
    return crc;
}

/* COBS-decode in[0..n) (no zero inside); the decoded length, or -1 if the block chain does
 * not end exactly at n. A code byte c < 255 stands for a zero after its c-1 data bytes,
 * unless it is the last block. */
static long cobs_decode(const unsigned char *in, size_t n, unsigned char *out) {
    size_t i = 0, o = 0;
    while (i < n) {
        unsigned code = in[i];
        if (code == 0 || i + code > n) return -1;
        memcpy(out + o, in + i + 1, code - 1);
        o += code - 1;
        i += code;
        if (code < 255 && i < n) out[o++] = 0;
    }
    return (long)o;
}

static unsigned long long le(const unsigned char *p, int n) {
    unsigned long long v = 0;
    for (int k = n - 1; k >= 0; k--) v = v << 8 | p[k];
    return v;
}

static long long unwrap(long long prev, unsigned long long raw, int bits) {
    unsigned long long mod = 1ULL << bits;
    long long delta = (long long)((raw - (unsigned long long)prev) & (mod - 1));
    if ((unsigned long long)delta >= mod / 2) delta -= (long long)mod;
    return prev + delta;
}

/* ---- §3, §6 rule 2: the layout check. Events in the body, 0 for a record, -1 invalid --- */
static int session_ok(const unsigned char *d, int m) {
    int kind = d[0] & 0x1F;
    if (kind == K_SESSION) {                    /* §3.7: 39-byte payload */
        uint32_t snr = (uint32_t)le(d + 23, 4);
        return m == 41 && (d[8] == 3 || d[8] == 4) && le(d + 13, 2) != 0 &&
               (snr & 0x7FFFFFFFu) <= 0x7F800000u;
    }
    if (kind == K_STIMULUS) return m >= 8 && d[6] >= 1 && d[6] <= 64 && m == 7 + d[6];
    if (kind == K_RUN_END) return m == 9 && d[8] <= 3;
    if (kind == K_SUITE) {                      /* §3.7: version, n_tasks, n, m, names */
        if (m < 7 || d[5] > 32 || d[6] > 32 || (d[5] == 0) != (d[6] == 0)) return 0;
        if (d[5] == 0 && le(d + 2, 2) != 0) return 0;
        return m == 7 + d[5] + d[6];
    }
    if (kind == K_TASK) {                       /* §3.7: task, k, tolerance, u, unit, classes */
        if (m < 9 || d[2] > 15 || d[3] > 24 || d[8] > 8 || m != 9 + d[8] + 4 * d[3]) return 0;
        if (le(d + 4, 4) >= 0x7F800000u) return 0;         /* tolerance finite and >= 0 */
        for (int c = 9 + d[8]; c < m; c += 4)
            if (((uint32_t)le(d + c, 4) & 0x7FFFFFFFu) > 0x7F800000u) return 0;  /* NaN */
        return 1;
    }
    return 0;                                   /* kinds 5..31 reserved: malformed */
}

static long check_body(const unsigned char *d, int m) {
    int typ = d[0] >> 5;
    if (m < 2) return -1;
    if (typ == T_WIDE) {                        /* §9.1 */
        long last = -1;
        if (m < 7 || (m - 4) % 3) return -1;
        for (int k = 4; k < m; k += 3) {
            unsigned long w = (unsigned long)le(d + k, 3), a = w >> 4;
            if (a >= WIDE_INVALID || ((w & 15) == 0 && (long)a <= last)) return -1;
            last = (long)a;
        }
        return (m - 4) / 3;
    }
    if (typ == T_SESSION) return session_ok(d, m) ? 0 : -1;
    if (typ != T_EVENTS) {
        if (BODY_LEN[typ] != m) return -1;
        if (typ == T_SYNC) {                    /* §3.2: version 3 or 4, step > 0 */
            unsigned long long step = le(d + 3, 2), base = le(d + 5, 6);
            if ((d[2] != 3 && d[2] != 4) || step == 0 || base >= MAX_TIME_US / step) return -1;
        }
        if (typ == T_MARKER && d[12] > 1) return -1;   /* §3.4: phase 0 or 1 */
        return 0;
    }
    if (m <= 4) return -1;                      /* §3.1: at least one event */
    long count = 0;
    int k = 4, last = -1;
    while (k < m) {
        if (k + 2 > m) return -1;
        unsigned w = d[k] | d[k + 1] << 8, a = w >> 7;
        if (w & 0x7F) last = -1;                /* a new step */
        if (a < N_NARROW) {
            if ((int)a <= last) return -1;      /* channels of a step ascend strictly */
            last = (int)a;
            count++;
            k += 2;
        } else if (a == 511) {                  /* bitmap: its whole step */
            if (k + 2 + BITMAP_BYTES > m || (d[k + 1 + BITMAP_BYTES] & 0xFC) || last >= 0)
                return -1;
            last = N_NARROW;
            long before = count;
            for (int q = k + 2; q < k + 2 + BITMAP_BYTES; q++)
                for (unsigned v = d[q]; v; v &= v - 1) count++;
            if (count == before) return -1;
            k += 2 + BITMAP_BYTES;
        } else {
            return -1;
        }
    }
    return count;
}

/* A candidate's decoded body length, -1 (COBS, length or CRC wrong) or -2 (layout wrong). */
static int try_frame(const unsigned char *p, size_t n, unsigned char *dec) {
    long m = cobs_decode(p, n, dec);
    if (m < 4 || crc16(dec, (size_t)m) != CRC_RESIDUE) return -1;
    if (m - 2 > MAX_BODY || check_body(dec, (int)m - 2) < 0) return -2;
    return (int)m - 2;
}

/* ---- output and the decoder under test ------------------------------------------------ */
static void dut_event(long long t_us, unsigned addr);
static void dut_marker(long long t_us, unsigned sid, int phase);
static void dut_session(unsigned n_channels, unsigned n_stimuli);

static void print_float(float f) {             /* the shortest decimal that reads back as f */
    char buf[32];
    if (isinf(f)) { printf("\"%sinf\"", f < 0 ? "-" : ""); return; }
    for (int p = 1; p <= 9; p++) {
        snprintf(buf, sizeof buf, "%.*g", p, (double)f);
        if (strtof(buf, NULL) == f) break;
    }
    printf("%s", buf);
}

static float float_at(const unsigned char *p) {   /* an IEEE-754 binary32, little-endian */
    float f;
    uint32_t bits = (uint32_t)le(p, 4);
    memcpy(&f, &bits, 4);
    return f;
}

static void print_text(const unsigned char *p, int n) {   /* UTF-8 bytes as a JSON string */
    putchar('"');
    for (int i = 0; i < n; i++) {
        unsigned char ch = p[i];
        if (ch == '"' || ch == '\\') printf("\\%c", ch);
        else if (ch < 0x20) printf("\\u%04x", ch);
        else putchar(ch);
    }
    putchar('"');
}

static void emit_event(decoder_t *D, long long t, unsigned a) {
    D->c.events_decoded++;
    if (json_out) printf("{\"event\":[%lld,%u]}\n", t, a);
    else dut_event(t, a);
}

/* §3.3, §7: unwrap the status counters, events_lost exact as of this status */
static void take_status(decoder_t *D, const unsigned char *d) {
    long long v[N_STATUS];
    for (int i = 0; i < N_STATUS; i++) {
        unsigned long long raw = le(d + 8 + 4 * i, 4);
        v[i] = (i == S_QUEUED || !D->have_status) ? (long long)raw
                                                  : unwrap(D->status_last[i], raw, 32);
        D->status_last[i] = v[i];
    }
    if (!D->have_status) { D->l0 = v[S_LINK]; D->d0 = D->c.events_decoded; }
    D->have_status = 1;
    D->c.events_lost = (v[S_LINK] - D->l0) - (D->c.events_decoded - D->d0);
    D->c.events_lost_reported = v[S_DROPPED];
    memcpy(D->status_value, v, sizeof v);
    D->status_t_us = (long long)le(d + 2, 6);
    D->status_running = d[0] & 1;
    if (json_out) {
        printf("{\"record\":{\"type\":\"STATUS\",\"t_us\":%lld,\"running\":%d",
               D->status_t_us, D->status_running);
        for (int i = 0; i < N_STATUS; i++)
            if (i != S_LINK) printf(",\"%s\":%lld", STATUS_NAMES[i], v[i]);
        printf("}}\n");
    }
}

static void take_record(decoder_t *D, const unsigned char *d, int m) {
    int typ = d[0] >> 5, low = d[0] & 0x1F;
    (void)m;
    if (typ == T_STATUS) { take_status(D, d); return; }
    if (typ == T_MARKER) {                       /* §3.4 */
        long long t = (long long)le(d + 2, 6);
        unsigned sid = (unsigned)le(d + 8, 4);
        if (json_out)
            printf("{\"record\":{\"type\":\"MARKER\",\"t_us\":%lld,\"stimulus_id\":%u,"
                   "\"phase\":%d}}\n", t, sid, d[12]);
        else dut_marker(t, sid, d[12]);
        return;
    }
    if (typ == T_COMMAND) {                      /* §3.5: another host's, on a shared link */
        unsigned token = (unsigned)le(d + 2, 2), op = d[4];
        uint32_t arg = (uint32_t)le(d + 5, 4);
        if (!json_out) return;
        if (op == 8) {
            printf("{\"record\":{\"type\":\"DECISION\",\"token\":%u,\"stimulus_id\":%u,"
                   "\"confidence\":%u}}\n", token, arg & 0xFFFFFF, arg >> 24);
        } else if (op == 10) {                   /* §3.5.3: ANSWER, task in bits 3..0 */
            unsigned task = arg & 0xF, f = arg >> 4;
            printf("{\"record\":{\"type\":\"ANSWER\",\"token\":%u,\"task\":%u,\"values\":[",
                   token, task);
            if (task == 0) printf("%u", f & 0xFFFFFF);
            else if (task == 1)                  /* two signed 14-bit steps of 0.01 mm */
                printf("%d,%d", (int)((f & 0x3FFF) ^ 0x2000) - 0x2000,
                       (int)(((f >> 14) & 0x3FFF) ^ 0x2000) - 0x2000);
            else if (task != 3) printf("%u", f); /* SLIP carries no value */
            printf("]}}\n");
        } else {
            printf("{\"record\":{\"type\":\"COMMAND\",\"token\":%u,\"opcode\":%u,\"arg\":",
                   token, op);
            if (op == 5 || op == 12) { float f; memcpy(&f, &arg, 4); print_float(f); }
            else printf("%u", arg);
            printf("}}\n");
        }
        return;
    }
    if (typ == T_ACK) {                          /* §3.6 */
        if (json_out)
            printf("{\"record\":{\"type\":\"ACK\",\"token\":%u,\"opcode\":%u,\"ok\":%d,"
                   "\"reason\":%u}}\n", (unsigned)le(d + 2, 2), d[4], low & 1, d[5]);
        return;
    }
    const unsigned char *p = d + 2;              /* §3.7: the payload */
    if (low == K_SESSION) {
        float snr;
        uint32_t bits = (uint32_t)le(p + 21, 4);
        memcpy(&snr, &bits, 4);
        D->have_session = 1;
        D->n_channels = (unsigned)le(p + 7, 4);
        D->n_stimuli = (unsigned)le(p + 18, 2);
        D->table_digest = (unsigned)le(p + 35, 4);
        if (json_out) {
            printf("{\"record\":{\"type\":\"SESSION\",\"t_us\":%lld,\"reason\":%u,"
                   "\"version\":%u,\"board_id\":%u,\"running\":%d,\"n_channels\":%u,"
                   "\"rows\":%u,\"cols\":%u,\"step_us\":%u,\"tick_us\":%u,\"snr_db\":",
                   (long long)le(p, 6), p[20], p[6], p[13], p[27] & 1, D->n_channels, p[25],
                   p[26], (unsigned)le(p + 11, 2), (unsigned)le(p + 14, 4));
            print_float(snr);
            printf(",\"response_window_us\":%u,\"n_stimuli\":%u,\"table_digest\":%u,"
                   "\"tasks\":%u,\"blind\":%d,\"held_object\":%d}}\n",
                   (unsigned)le(p + 28, 4), D->n_stimuli, D->table_digest,
                   (unsigned)le(p + 32, 2), (p[27] >> 1) & 1, (p[27] >> 2) & 1);
        } else {
            dut_session(D->n_channels, D->n_stimuli);
        }
    } else if (low == K_STIMULUS) {
        if (json_out) {
            printf("{\"record\":{\"type\":\"STIMULUS\",\"stimulus_id\":%u,\"name\":",
                   (unsigned)le(p, 4));
            print_text(p + 5, p[4]);
            printf("}}\n");
        }
    } else if (low == K_SUITE) {
        if (json_out) {
            printf("{\"record\":{\"type\":\"SUITE\",\"name\":");
            print_text(p + 5, p[3]);
            printf(",\"version\":%u,\"case\":", (unsigned)le(p, 2));
            print_text(p + 5 + p[3], p[4]);
            printf(",\"n_tasks\":%u}}\n", p[2]);
        }
    } else if (low == K_TASK) {
        if (json_out) {
            float tol = float_at(p + 2);
            printf("{\"record\":{\"type\":\"TASK\",\"task\":%u,\"tolerance\":", p[0]);
            if (tol == 0) printf("null");
            else print_float(tol);
            printf(",\"unit\":");
            print_text(p + 7, p[6]);
            printf(",\"classes\":[");
            for (int i = 0; i < p[1]; i++) {
                if (i) putchar(',');
                print_float(float_at(p + 7 + p[6] + 4 * i));
            }
            printf("]}}\n");
        }
    } else {                                     /* K_RUN_END */
        D->run_ended = 1;
        D->run_end_reason = p[6];
        if (json_out)
            printf("{\"record\":{\"type\":\"RUN_END\",\"t_us\":%lld,\"reason\":%u}}\n",
                   (long long)le(p, 6), p[6]);
    }
}

/* §6 rule 4: NEW (0), DUPLICATE (1) or LATE (2) */
static int take_seq(decoder_t *D, int command, int seq) {
    int *have = command ? &D->have_cmd_seq : &D->have_seq;
    int *last = command ? &D->cmd_seq : &D->seq;
    if (*have) {
        int gap = (seq - *last - 1) & 0xFF;
        if (gap == 255) { D->c.duplicates++; return 1; }
        if (!command && gap >= 255 - LATE_WINDOW) { D->c.late_frames++; return 2; }
        if (gap && command) { D->c.command_seq_gaps++; D->c.commands_lost += gap; }
        else if (gap) {
            D->c.seq_gaps++;
            D->c.frames_lost += gap;
            if (gap >= EPOCH_GAP) D->sync_valid = 0;
        }
    }
    *have = 1;
    *last = seq;
    return 0;
}

/* §6 rule 5: the time base; returns whether it is valid after this SYNC */
static int take_base(decoder_t *D, unsigned long long raw) {
    const long long jump = 1LL << 44;
    long long u = unwrap(D->base, raw, 48);
    if (llabs(u - D->base) <= jump) { D->base = u; D->have_cand = 0; return 1; }
    if (D->have_cand) {
        long long v = unwrap(D->cand, raw, 48);
        if (llabs(v - D->cand) <= jump) { D->base = v; D->have_cand = 0; return 1; }
    }
    D->cand = (long long)raw;
    D->have_cand = 1;
    return 0;
}

/* One good packet body d[0..m) */
static void take_packet(decoder_t *D, const unsigned char *d, int m) {
    int typ = d[0] >> 5;
    int verdict = take_seq(D, typ == T_COMMAND, d[1]);
    int events = typ == T_EVENTS || typ == T_WIDE;
    if (verdict == 2 && events) D->c.events_untimed += check_body(d, m);
    if (verdict != 0) return;
    D->c.frames_ok++;
    if (events) {
        long long t;
        if (!D->sync_valid || (d[0] & 0x1F) != D->epoch) {   /* never guess a time */
            D->c.events_untimed += check_body(d, m);
            return;
        }
        t = D->base + (long long)le(d + 2, 2);
        if (typ == T_WIDE) {                                  /* §9.1 */
            for (int k = 4; k < m; k += 3) {
                unsigned long w = (unsigned long)le(d + k, 3);
                t += (long long)(w & 15);
                emit_event(D, t * D->step_us, (unsigned)(w >> 4));
            }
            return;
        }
        for (int k = 4; k < m;) {                             /* §3.1 */
            unsigned w = d[k] | d[k + 1] << 8, a = w >> 7;
            t += w & 0x7F;
            if (a < N_NARROW) { emit_event(D, t * D->step_us, a); k += 2; continue; }
            for (int q = 0; q < BITMAP_BYTES; q++)
                for (int bit = 0; bit < 8; bit++)
                    if (d[k + 2 + q] >> bit & 1) emit_event(D, t * D->step_us, 8u * q + bit);
            k += 2 + BITMAP_BYTES;
        }
    } else if (typ == T_SYNC) {                               /* §3.2, §6 rule 5 */
        D->sync_valid = 1;
        D->epoch = d[0] & 0x1F;
        if (D->have_base) D->sync_valid = take_base(D, le(d + 5, 6));
        else D->base = (long long)le(d + 5, 6);
        D->have_base = 1;
        D->step_us = (long long)le(d + 3, 2);
        D->c.syncs++;
    } else {
        take_record(D, d, m);
    }
}

/* §6 rules 2-3: one candidate (the bytes between two delimiters), with resynchronisation */
static void take_candidate(decoder_t *D, const unsigned char *p, size_t n) {
    static unsigned char dec[MAX_WIRE + 8];
    size_t first = 0, k;
    int m;
    if (n == 0) return;
    if (n > MAX_WIRE) {                     /* cut to its last 1032 bytes */
        D->c.crc_errors++;
        D->c.bytes_discarded += (long long)(n - MAX_WIRE);
        first = n - MAX_WIRE;
        k = first;
    } else {
        m = try_frame(p, n, dec);
        if (m >= 0) { take_packet(D, dec, m); return; }
        if (m == -2) D->c.malformed++; else D->c.crc_errors++;
        k = 1;
    }
    /* the first (longest) suffix that is a good packet: quadratic here for brevity; the
     * reference checks every suffix's CRC in one pass (§6 rule 3) */
    for (; k < n; k++) {
        m = try_frame(p + k, n - k, dec);
        if (m >= 0) {
            D->c.resyncs++;
            D->c.bytes_discarded += (long long)(k - first);
            take_packet(D, dec, m);
            return;
        }
    }
    D->c.bytes_discarded += (long long)(n - first);
}

/* Feed received bytes in any chunking (§6 rule 1) */
static void feed(decoder_t *D, const unsigned char *buf, size_t n) {
    for (size_t i = 0; i < n; i++) {
        if (buf[i] == 0) {
            take_candidate(D, D->pending, D->npending);
            D->npending = 0;
            continue;
        }
        if (D->npending == 2 * MAX_WIRE) {   /* no delimiter: keep the last 1032 bytes */
            memmove(D->pending, D->pending + MAX_WIRE, MAX_WIRE);
            D->npending = MAX_WIRE;
            D->c.bytes_discarded += MAX_WIRE;
        }
        D->pending[D->npending++] = buf[i];
    }
}

static void print_counters(const decoder_t *D) {
    const counters_t *c = &D->c;
    printf("{\"frames_ok\":%lld,\"crc_errors\":%lld,\"malformed\":%lld,\"resyncs\":%lld,"
           "\"bytes_discarded\":%lld,\"seq_gaps\":%lld,\"frames_lost\":%lld,"
           "\"duplicates\":%lld,\"late_frames\":%lld,\"events_decoded\":%lld,"
           "\"events_untimed\":%lld,\"events_lost\":%lld,\"events_lost_reported\":%lld,"
           "\"syncs\":%lld,\"command_seq_gaps\":%lld,\"commands_lost\":%lld}",
           c->frames_ok, c->crc_errors, c->malformed, c->resyncs, c->bytes_discarded,
           c->seq_gaps, c->frames_lost, c->duplicates, c->late_frames, c->events_decoded,
           c->events_untimed, c->events_lost, c->events_lost_reported, c->syncs,
           c->command_seq_gaps, c->commands_lost);
}

/* ---- the decoder under test (the rule of the header comment) -------------------------- */
#define BIN_US 5000
#define WINDOW_US 30000
#define REFRACTORY_US 200000
#define MAX_IDS 4096
#define TRUTH 16

static struct {
    unsigned n_ch, n_ids;
    long long bin, onset, last_onset;
    double baseline, *window, *sums; /* window[n_ch]; sums[MAX_IDS][n_ch] on demand */
    int open, have_sum[MAX_IDS];
    unsigned bin_n, *bin_addr, bin_cap;
    long long truth_t[TRUTH];
    unsigned truth_id[TRUTH], truth_n;
    unsigned decisions;
} dut = {N_NARROW, 0, -1, 0, -REFRACTORY_US, 0, 0, 0, 0, {0}, 0, 0, 0, {0}, {0}, 0, 0};

static void (*send_decision)(unsigned sid, double confidence);

static void dut_session(unsigned n_channels, unsigned n_stimuli) {
    /* configure from the stream (§3.7): the channel count sizes every feature vector */
    if (dut.window && n_channels == dut.n_ch) return;
    free(dut.window);
    free(dut.sums);
    dut.n_ch = n_channels ? n_channels : N_NARROW;
    dut.window = calloc(dut.n_ch, sizeof(double));
    dut.sums = NULL;
    memset(dut.have_sum, 0, sizeof dut.have_sum);
    dut.n_ids = n_stimuli;
}

static void dut_marker(long long t_us, unsigned sid, int phase) {
    if (phase != 0 || sid >= MAX_IDS) return;   /* ONSETs of ids we can hold */
    dut.truth_t[dut.truth_n % TRUTH] = t_us;
    dut.truth_id[dut.truth_n % TRUTH] = sid;
    dut.truth_n++;
}

static void dut_decide(void) {
    double norm = 0, best = -2;
    int best_id = -1;
    unsigned n = dut.n_ch;
    for (unsigned i = 0; i < n; i++) norm += dut.window[i] * dut.window[i];
    norm = sqrt(norm) > 1e-9 ? sqrt(norm) : 1e-9;
    for (unsigned i = 0; i < n; i++) dut.window[i] /= norm;
    for (int id = 0; id < MAX_IDS; id++) {
        if (!dut.have_sum[id]) continue;
        double dot = 0, sn = 0, *s = dut.sums + (size_t)id * n;
        for (unsigned i = 0; i < n; i++) { dot += dut.window[i] * s[i]; sn += s[i] * s[i]; }
        dot /= sqrt(sn) > 1e-9 ? sqrt(sn) : 1e-9;
        if (dot > best) { best = dot; best_id = id; }
    }
    if (best_id >= 0) {
        send_decision((unsigned)best_id, best < 0 ? 0 : best > 1 ? 1 : best);
        dut.decisions++;
    }
    /* learn from a true onset: a marker at most 50 ms before the onset bin's end */
    int learn = -1;
    for (unsigned j = 0; j < TRUTH && j < dut.truth_n; j++) {
        unsigned i = (dut.truth_n - 1 - j) % TRUTH;
        long long d = dut.onset + BIN_US - dut.truth_t[i];
        if (d >= 0 && d <= 50000) { learn = (int)dut.truth_id[i]; break; }
    }
    if (learn >= 0) {
        if (!dut.sums) dut.sums = calloc((size_t)MAX_IDS * n, sizeof(double));
        for (unsigned i = 0; i < n; i++) dut.sums[(size_t)learn * n + i] += dut.window[i];
        dut.have_sum[learn] = 1;
    }
    dut.open = 0;
}

static void dut_close_bin(void) {
    long long start = dut.bin * BIN_US;
    if (dut.open && start + BIN_US >= dut.onset + WINDOW_US) {
        dut_decide();
    } else if (!dut.open && start - dut.last_onset >= REFRACTORY_US &&
               dut.bin_n > 3 * dut.baseline + 5) {
        dut.last_onset = dut.onset = start;
        dut.open = 1;
        memset(dut.window, 0, dut.n_ch * sizeof(double));
        for (unsigned i = 0; i < dut.bin_n; i++) dut.window[dut.bin_addr[i]] += 1;
    } else if (!dut.open) {
        dut.baseline += 0.02 * (dut.bin_n - dut.baseline);
    }
    dut.bin++;
    dut.bin_n = 0;
}

static void dut_event(long long t_us, unsigned addr) {
    if (!dut.window) dut_session(N_NARROW, 0);
    if (addr >= dut.n_ch) return;
    if (dut.bin < 0) dut.bin = t_us / BIN_US;
    while (t_us / BIN_US > dut.bin) dut_close_bin();
    if (dut.bin_n == dut.bin_cap) {
        dut.bin_cap = dut.bin_cap ? 2 * dut.bin_cap : 1024;
        dut.bin_addr = realloc(dut.bin_addr, dut.bin_cap * sizeof(unsigned));
    }
    dut.bin_addr[dut.bin_n++] = addr;
    if (dut.open) dut.window[addr] += 1;
}

/* ---- the link: a tty or UDP; DECISIONs are COMMAND packets of our own (§3.5, §2) ------ */
static int fd_link = -1, is_udp;
static struct sockaddr_in peer;
static socklen_t peer_len;
static unsigned cmd_seq, cmd_token;
static volatile sig_atomic_t stop_now;

static size_t cobs_frame(const unsigned char *body, size_t n, unsigned char *out) {
    unsigned char buf[MAX_BODY + 2];
    unsigned crc;
    size_t o = 1, code_pos = 0;
    unsigned code = 1;
    memcpy(buf, body, n);
    crc = crc16(buf, n) ^ 0xFFFF;               /* CRC-16/GENIBUS: final XOR 0xFFFF */
    buf[n] = (unsigned char)(crc >> 8);         /* appended big-endian (§2) */
    buf[n + 1] = (unsigned char)crc;
    for (size_t i = 0; i < n + 2; i++) {
        if (buf[i] == 0) { out[code_pos] = (unsigned char)code; code_pos = o++; code = 1; }
        else {
            out[o++] = buf[i];
            if (++code == 255) { out[code_pos] = 255; code_pos = o++; code = 1; }
        }
    }
    out[code_pos] = (unsigned char)code;
    out[o++] = 0;
    return o;
}

static void link_decision(unsigned sid, double confidence) {
    unsigned char body[9], wire[32];
    uint32_t arg = (sid & 0xFFFFFF) | (uint32_t)lround(confidence * 254) << 24;  /* §3.5.1 */
    cmd_token = (cmd_token + 1) & 0xFFFF;
    body[0] = T_COMMAND << 5;
    body[1] = (unsigned char)(cmd_seq++ & 0xFF);    /* our own sequence counter (§3.5) */
    body[2] = cmd_token & 0xFF;
    body[3] = cmd_token >> 8;
    body[4] = 8;                                    /* DECISION */
    for (int i = 0; i < 4; i++) body[5 + i] = (unsigned char)(arg >> (8 * i));
    size_t n = cobs_frame(body, sizeof body, wire);
    if (is_udp) sendto(fd_link, wire, n, 0, (struct sockaddr *)&peer, peer_len);
    else if (write(fd_link, wire, n) < 0) perror("write");
}

static void on_signal(int sig) { (void)sig; stop_now = 1; }

static int open_tty(const char *path, long baud) {
    struct termios tio;
    int fd = open(path, O_RDWR | O_NOCTTY);
    if (fd < 0) { perror(path); exit(2); }
    if (tcgetattr(fd, &tio) == 0) {
        cfmakeraw(&tio);                        /* 8N1, no echo, no translation */
        speed_t s = baud >= 921600 ? B921600 : baud >= 460800 ? B460800 :
                    baud >= 230400 ? B230400 : baud >= 115200 ? B115200 : B9600;
        cfsetispeed(&tio, s);
        cfsetospeed(&tio, s);
        tcsetattr(fd, TCSANOW, &tio);
    }
    return fd;
}

static int open_udp(const char *hostport) {
    char host[64];
    const char *colon = strrchr(hostport, ':');
    struct sockaddr_in a;
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (!colon || colon - hostport >= (long)sizeof host) {
        fprintf(stderr, "skin_decoder: --udp HOST:PORT\n");
        exit(2);
    }
    memcpy(host, hostport, (size_t)(colon - hostport));
    host[colon - hostport] = 0;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((unsigned short)atoi(colon + 1));
    if (inet_pton(AF_INET, host, &a.sin_addr) != 1 || bind(fd, (struct sockaddr *)&a, sizeof a)) {
        perror(hostport);
        exit(2);
    }
    return fd;
}

int main(int argc, char **argv) {
    static decoder_t D;
    static unsigned char buf[65536];
    const char *tty = NULL, *udp = NULL;
    long baud = 921600;
    double idle_s = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--tty") && i + 1 < argc) tty = argv[++i];
        else if (!strcmp(argv[i], "--udp") && i + 1 < argc) udp = argv[++i];
        else if (!strcmp(argv[i], "--baud") && i + 1 < argc) baud = atol(argv[++i]);
        else if (!strcmp(argv[i], "--idle") && i + 1 < argc) idle_s = atof(argv[++i]);
        else if (!strcmp(argv[i], "--stdin")) json_out = 1;
        else {
            fprintf(stderr, "usage: skin_decoder --tty PATH [--baud N] | --udp HOST:PORT | "
                            "--stdin  [--idle SECONDS]\n");
            return 2;
        }
    }
    if (json_out) {                              /* conformance: bytes in, JSON lines out */
        ssize_t n;
        while ((n = read(0, buf, sizeof buf)) > 0) feed(&D, buf, (size_t)n);
        printf("{\"counters\":");
        print_counters(&D);
        printf("}\n");
        return 0;
    }
    if (!tty == !udp) { fprintf(stderr, "skin_decoder: give --tty PATH or --udp HOST:PORT\n"); return 2; }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    send_decision = link_decision;
    is_udp = udp != NULL;
    fd_link = is_udp ? open_udp(udp) : open_tty(tty, baud);
    time_t last_data = time(NULL);
    while (!stop_now && !D.run_ended) {          /* RUN_END: the board said the run is over */
        fd_set r;
        struct timeval tv = {0, 100000};
        FD_ZERO(&r);
        FD_SET(fd_link, &r);
        if (select(fd_link + 1, &r, NULL, NULL, &tv) < 0) { if (errno == EINTR) continue; break; }
        if (!FD_ISSET(fd_link, &r)) {
            if (idle_s > 0 && difftime(time(NULL), last_data) > idle_s) break;
            continue;
        }
        ssize_t n;
        if (is_udp) {
            peer_len = sizeof peer;
            n = recvfrom(fd_link, buf, sizeof buf, 0, (struct sockaddr *)&peer, &peer_len);
        } else {
            n = read(fd_link, buf, sizeof buf);
        }
        if (n <= 0) { if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue; break; }
        last_data = time(NULL);
        feed(&D, buf, (size_t)n);
    }
    printf("{\"counters\":");
    print_counters(&D);
    printf(",\"status\":{\"t_us\":%lld", D.status_t_us);
    for (int i = 0; i < N_STATUS; i++)
        if (i != S_LINK) printf(",\"%s\":%lld", STATUS_NAMES[i], D.status_value[i]);
    printf("},\"session\":{\"seen\":%d,\"n_channels\":%u,\"n_stimuli\":%u,"
           "\"table_digest\":%u},\"run_end\":%d,\"run_end_reason\":%d,\"decisions\":%u}\n",
           D.have_session, D.n_channels, D.n_stimuli, D.table_digest, D.run_ended,
           D.run_ended ? D.run_end_reason : -1, dut.decisions);
    return 0;
}
