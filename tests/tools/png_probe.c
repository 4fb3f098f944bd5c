/* png_probe — what the browser test needs to know of a screenshot: how
 * much of a rectangle is not background, and how many shades it holds
 * (a drawn, lit model has many; a blank or flat canvas one or two).
 *
 * usage: png_probe FILE.png X0 Y0 X1 Y1
 * prints: "WIDTH HEIGHT COVERED SHADES" where COVERED is the per mille of
 * the rectangle's pixels that differ from its top-left pixel (the
 * background) by more than 24 in a channel, and SHADES the number of
 * distinct colours after quantising each channel to 16 levels.
 *
 * Reads 8-bit RGB or RGBA non-interlaced PNGs (what Chromium writes);
 * anything else is an error naming the file and the reason. */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 |
           p[3];
}

static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

static int fail(const char *file, const char *why)
{
    fprintf(stderr, "png_probe: %s: %s\n", file, why);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: png_probe FILE.png X0 Y0 X1 Y1\n");
        return 2;
    }
    const char *file = argv[1];
    FILE *f = fopen(file, "rb");
    if (!f)
        return fail(file, strerror(errno));
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *d = size > 0 ? malloc((size_t)size) : NULL;
    if (!d || fread(d, 1, (size_t)size, f) != (size_t)size) {
        fclose(f);
        return fail(file, "cannot read");
    }
    fclose(f);
    if (size < 33 || memcmp(d, "\x89PNG\r\n\x1a\n", 8) != 0)
        return fail(file, "not a PNG");
    uint32_t w = 0, h = 0;
    int bpp = 0;
    unsigned char *idat = NULL;
    size_t ilen = 0;
    for (long o = 8; o + 12 <= size;) {
        uint32_t n = be32(d + o);
        const unsigned char *type = d + o + 4, *data = d + o + 8;
        if ((long)n > size - o - 12)
            return fail(file, "truncated chunk");
        if (memcmp(type, "IHDR", 4) == 0) {
            w = be32(data);
            h = be32(data + 4);
            if (data[8] != 8 || (data[9] != 2 && data[9] != 6) || data[12])
                return fail(file, "not 8-bit RGB/RGBA non-interlaced");
            bpp = data[9] == 6 ? 4 : 3;
        } else if (memcmp(type, "IDAT", 4) == 0) {
            unsigned char *g = realloc(idat, ilen + n);
            if (!g)
                return fail(file, "out of memory");
            idat = g;
            memcpy(idat + ilen, data, n);
            ilen += n;
        }
        o += 12 + (long)n;
    }
    if (!bpp || !idat || w == 0 || h == 0 || w > 20000 || h > 20000)
        return fail(file, "no image");
    size_t stride = (size_t)w * bpp, rawlen = (stride + 1) * h;
    unsigned char *raw = malloc(rawlen), *img = malloc(stride * h);
    uLongf got = rawlen;
    if (!raw || !img || uncompress(raw, &got, idat, ilen) != Z_OK ||
        got != rawlen)
        return fail(file, "bad image data");
    for (uint32_t y = 0; y < h; y++) {
        const unsigned char *in = raw + y * (stride + 1) + 1;
        unsigned char *out = img + y * stride, *up = y ? out - stride : NULL;
        int ft = in[-1];
        for (size_t x = 0; x < stride; x++) {
            int a = x >= (size_t)bpp ? out[x - bpp] : 0, b = up ? up[x] : 0;
            int c = up && x >= (size_t)bpp ? up[x - bpp] : 0, v = in[x];
            switch (ft) {
            case 0: break;
            case 1: v += a; break;
            case 2: v += b; break;
            case 3: v += (a + b) / 2; break;
            case 4: v += paeth(a, b, c); break;
            default: return fail(file, "bad filter type");
            }
            out[x] = (unsigned char)v;
        }
    }
    long x0 = atol(argv[2]), y0 = atol(argv[3]), x1 = atol(argv[4]),
         y1 = atol(argv[5]);
    if (x0 < 0 || y0 < 0 || x1 > (long)w || y1 > (long)h || x0 >= x1 ||
        y0 >= y1)
        return fail(file, "rectangle outside the image");
    const unsigned char *bg = img + (size_t)y0 * stride + (size_t)x0 * bpp;
    static unsigned char seen[4096];
    long covered = 0, shades = 0, total = (x1 - x0) * (y1 - y0);
    for (long y = y0; y < y1; y++)
        for (long x = x0; x < x1; x++) {
            const unsigned char *p = img + (size_t)y * stride + (size_t)x * bpp;
            int diff = 0;
            for (int k = 0; k < 3; k++)
                diff |= abs(p[k] - bg[k]) > 24;
            covered += diff;
            unsigned q = (unsigned)(p[0] >> 4) << 8 | (p[1] >> 4) << 4 |
                         p[2] >> 4;
            if (!seen[q]) {
                seen[q] = 1;
                shades++;
            }
        }
    printf("%u %u %ld %ld\n", w, h, covered * 1000 / total, shades);
    free(d);
    free(idat);
    free(raw);
    free(img);
    return 0;
}
