/* LTC read by libltc (Debian's libltc-dev), the independent decoder that LTC indra writes is
 * tested against: signed 16-bit mono samples at RATE Hz on stdin, one line out per frame read:
 *   HH:MM:SS:FF START END REVERSE
 * START and END are the samples where libltc found the frame's first and last transitions;
 * REVERSE is 1 for code played backwards. FPS is the code's nominal rate (24, 25, 29.97, 30).
 *
 * Usage: ltcread RATE FPS < samples
 * Build: cc -O2 -o ltcread ltcread.c -lltc
 */
#include <ltc.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: ltcread RATE FPS < samples\n");
        return 2;
    }
    double rate = atof(argv[1]), fps = atof(argv[2]);
    LTCDecoder *decoder = ltc_decoder_create((int)(rate / fps), 32);
    if (!decoder) {
        fprintf(stderr, "ltcread: no decoder\n");
        return 1;
    }
    short buffer[1024];
    ltc_off_t position = 0;
    size_t n;
    LTCFrameExt frame;
    SMPTETimecode label;
    while ((n = fread(buffer, sizeof buffer[0], 1024, stdin)) > 0) {
        ltc_decoder_write_s16(decoder, buffer, n, position);
        position += (ltc_off_t)n;
        while (ltc_decoder_read(decoder, &frame)) {
            ltc_frame_to_time(&label, &frame.ltc, 0);
            printf("%02d:%02d:%02d:%02d %lld %lld %d\n", label.hours, label.mins, label.secs, label.frame,
                   (long long)frame.off_start, (long long)frame.off_end, frame.reverse);
        }
    }
    ltc_decoder_free(decoder);
    return 0;
}
