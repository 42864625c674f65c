/* LTC from libltc (Debian's libltc-dev), the independent encoder indra's decoder is tested
 * against, written to stdout as unsigned 8-bit mono samples at RATE Hz (libltc's own sample
 * format). The code is given as segments, one encoder throughout (its level carries on from
 * one segment to the next, as a desk's output does when its transport jumps):
 *   HH:MM:SS:FF+N   N frames from that label, counting up;
 *   HH:MM:SS:FF-N   N frames from that label played backwards, counting down;
 *   silence+N       N frames' worth of silence (a dropout).
 * FPS is 24, 25, 29.97 (drop-frame) or 30.
 *
 * Usage: ltcgen RATE FPS SEGMENT...
 * Build: cc -O2 -o ltcgen ltcgen.c -lltc
 */
#include <ltc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: ltcgen RATE FPS SEGMENT...\n");
        return 2;
    }
    double rate = atof(argv[1]), fps = atof(argv[2]);
    int drop = fps > 29.9 && fps < 29.99;
    enum LTC_TV_STANDARD standard = fps == 25 ? LTC_TV_625_50 : fps == 24 ? LTC_TV_FILM_24 : LTC_TV_525_60;
    LTCEncoder *encoder = ltc_encoder_create(rate, fps, standard, 0);
    if (!encoder) {
        fprintf(stderr, "ltcgen: no encoder\n");
        return 1;
    }
    ltcsnd_sample_t *buffer = malloc(ltc_encoder_get_buffersize(encoder));
    double owed = 0; /* silence: samples a frame is long, with the fraction carried */
    for (int a = 3; a < argc; a++) {
        unsigned h, m, s, f;
        long count;
        char sign;
        if (sscanf(argv[a], "silence+%ld", &count) == 1) {
            for (long i = 0; i < count; i++) {
                owed += rate / (drop ? 30000.0 / 1001.0 : fps);
                for (; owed >= 1; owed -= 1) {
                    putchar(128);
                }
            }
            continue;
        }
        if (sscanf(argv[a], "%u:%u:%u:%u%c%ld", &h, &m, &s, &f, &sign, &count) != 6 || (sign != '+' && sign != '-')) {
            fprintf(stderr, "ltcgen: '%s' is not HH:MM:SS:FF+N, HH:MM:SS:FF-N or silence+N\n", argv[a]);
            return 2;
        }
        SMPTETimecode start;
        memset(&start, 0, sizeof start);
        strcpy(start.timezone, "+0000");
        start.months = 1;
        start.days = 1;
        start.hours = h;
        start.mins = m;
        start.secs = s;
        start.frame = f;
        ltc_encoder_set_timecode(encoder, &start);
        LTCFrame frame;
        ltc_encoder_get_frame(encoder, &frame);
        frame.dfbit = drop;
        ltc_encoder_set_frame(encoder, &frame);
        for (long i = 0; i < count; i++) {
            if (sign == '-') {
                ltc_encoder_encode_reversed_frame(encoder);
            } else {
                ltc_encoder_encode_frame(encoder);
            }
            int n = ltc_encoder_copy_buffer(encoder, buffer);
            fwrite(buffer, 1, (size_t)n, stdout);
            if (sign == '-') {
                ltc_encoder_dec_timecode(encoder);
            } else {
                ltc_encoder_inc_timecode(encoder);
            }
        }
    }
    free(buffer);
    ltc_encoder_free(encoder);
    return 0;
}
