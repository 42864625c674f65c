/* LTC from libltc (Debian's libltc-dev), the independent encoder indra's decoder is tested
 * against: COUNT frames from HH:MM:SS:FF at FPS (24, 25, 29.97 = drop-frame, 30), written to
 * stdout as unsigned 8-bit mono samples at RATE Hz (libltc's own sample format).
 *
 * Usage: ltcgen RATE FPS HH:MM:SS:FF COUNT [reverse]
 * Build: cc -O2 -o ltcgen ltcgen.c -lltc
 */
#include <ltc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: ltcgen RATE FPS HH:MM:SS:FF COUNT [reverse]\n");
        return 2;
    }
    double rate = atof(argv[1]), fps = atof(argv[2]);
    long count = atol(argv[4]);
    int reverse = argc > 5 && strcmp(argv[5], "reverse") == 0;
    int drop = fps > 29.9 && fps < 29.99;
    enum LTC_TV_STANDARD standard = fps == 25 ? LTC_TV_625_50 : fps == 24 ? LTC_TV_FILM_24 : LTC_TV_525_60;
    SMPTETimecode start;
    memset(&start, 0, sizeof start);
    strcpy(start.timezone, "+0000");
    start.years = 0; start.months = 1; start.days = 1;
    unsigned h, m, s, f;
    if (sscanf(argv[3], "%u:%u:%u:%u", &h, &m, &s, &f) != 4) {
        fprintf(stderr, "ltcgen: '%s' is not HH:MM:SS:FF\n", argv[3]);
        return 2;
    }
    start.hours = h; start.mins = m; start.secs = s; start.frame = f;
    LTCEncoder *encoder = ltc_encoder_create(rate, fps, standard, 0);
    if (!encoder) {
        fprintf(stderr, "ltcgen: no encoder\n");
        return 1;
    }
    ltc_encoder_set_timecode(encoder, &start);
    LTCFrame frame;
    ltc_encoder_get_frame(encoder, &frame);
    frame.dfbit = drop;
    ltc_encoder_set_frame(encoder, &frame);
    ltcsnd_sample_t *buffer = malloc(ltc_encoder_get_buffersize(encoder));
    for (long i = 0; i < count; i++) {
        if (reverse) {
            ltc_encoder_encode_reversed_frame(encoder);
        } else {
            ltc_encoder_encode_frame(encoder);
        }
        int n = ltc_encoder_copy_buffer(encoder, buffer);
        fwrite(buffer, 1, (size_t)n, stdout);
        if (reverse) {
            ltc_encoder_dec_timecode(encoder);
        } else {
            ltc_encoder_inc_timecode(encoder);
        }
    }
    free(buffer);
    ltc_encoder_free(encoder);
    return 0;
}
