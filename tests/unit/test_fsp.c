/* test_fsp.c — the FSP/1 codec: CRC-32 check values, the exact byte layout
 * of a frame, decoding under every split of a byte stream, resync after
 * bad magic / bad CRC / oversized lengths, the payload limit, and the
 * strict payload parsers. */
#include "testutil.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "crc32.h"
#include "fsp.h"

typedef struct rec {
    int kind;
    uint8_t type;
    uint16_t seq;
    uint32_t len;
    uint32_t crc; /* of the payload, to compare contents */
} rec;

typedef struct log {
    rec ev[256];
    size_t n;
} log;

static void record(log *l, const proto_fsp_event *ev)
{
    assert_true(l->n < 256);
    rec *r = &l->ev[l->n++];
    r->kind = ev->kind;
    r->type = ev->frame.type;
    r->seq = ev->frame.seq;
    r->len = ev->frame.len;
    r->crc = ev->kind == PROTO_FSP_EV_FRAME
                 ? proto_crc32(ev->frame.payload, ev->frame.len)
                 : 0;
}

/* Feeds data in pieces cut at the sorted positions cuts[0..ncuts), then
 * drains, recording every event. */
static void feed_cuts(proto_fsp_decoder *d, const uint8_t *data, size_t len,
                      const size_t *cuts, size_t ncuts, log *l)
{
    size_t start = 0;
    for (size_t c = 0; c <= ncuts; c++) {
        size_t end = c < ncuts ? cuts[c] : len;
        const uint8_t *p = data + start;
        size_t n = end - start;
        proto_fsp_event ev;
        do {
            size_t used = proto_fsp_decode(d, p, n, &ev);
            assert_true(used <= n);
            assert_true(used > 0 || ev.kind != PROTO_FSP_EV_NONE || n == 0);
            p += used;
            n -= used;
            if (ev.kind != PROTO_FSP_EV_NONE)
                record(l, &ev);
        } while (n > 0 || ev.kind != PROTO_FSP_EV_NONE);
        start = end;
    }
}

static void feed_all(proto_fsp_decoder *d, const uint8_t *data, size_t len,
                     log *l)
{
    feed_cuts(d, data, len, NULL, 0, l);
}

/* Appends one frame to buf at *n. */
static void put_frame(uint8_t *buf, size_t cap, size_t *n, uint8_t type,
                      uint16_t seq, const void *payload, size_t len)
{
    size_t sz;
    assert_int_equal(proto_fsp_encode(type, seq, payload, len, buf + *n,
                                      cap - *n, &sz),
                     0);
    assert_int_equal(sz, len + PROTO_FSP_OVERHEAD);
    *n += sz;
}

/* A stream of five frames of assorted types and sizes. */
static size_t sample_stream(uint8_t *buf, size_t cap, log *expect)
{
    static uint8_t big[3000];
    for (size_t i = 0; i < sizeof big; i++)
        big[i] = (uint8_t)(i * 7 + 3);
    const char *hello = "{\"host\":\"facetd\",\"version\":\"0.1.0\"}";
    uint8_t ack[2];
    proto_fsp_build_seq(ack, 7);
    size_t n = 0;
    struct {
        uint8_t type;
        uint16_t seq;
        const void *p;
        size_t len;
    } fr[] = {
        {PROTO_FSP_HELLO, 0, hello, strlen(hello)},
        {PROTO_FSP_GET_INFO, 1, NULL, 0},
        {PROTO_FSP_MODEL, 2, big, sizeof big},
        {PROTO_FSP_ACK, 65535, ack, 2},
        {PROTO_FSP_ABORT, 0, NULL, 0},
    };
    for (size_t i = 0; i < 5; i++) {
        put_frame(buf, cap, &n, fr[i].type, fr[i].seq, fr[i].p, fr[i].len);
        if (expect) {
            rec *r = &expect->ev[expect->n++];
            r->kind = PROTO_FSP_EV_FRAME;
            r->type = fr[i].type;
            r->seq = fr[i].seq;
            r->len = (uint32_t)fr[i].len;
            r->crc = proto_crc32(fr[i].p, fr[i].len);
        }
    }
    return n;
}

static void assert_logs_equal(const log *a, const log *b)
{
    assert_int_equal(a->n, b->n);
    for (size_t i = 0; i < a->n; i++) {
        assert_int_equal(a->ev[i].kind, b->ev[i].kind);
        assert_int_equal(a->ev[i].type, b->ev[i].type);
        assert_int_equal(a->ev[i].seq, b->ev[i].seq);
        assert_int_equal(a->ev[i].len, b->ev[i].len);
        assert_int_equal(a->ev[i].crc, b->ev[i].crc);
    }
}

static void test_crc32_check_value_and_incremental(void **state)
{
    (void)state;
    const char *s = "123456789";
    assert_int_equal(proto_crc32(s, 9), 0xCBF43926u);
    assert_int_equal(proto_crc32(NULL, 0), 0);
    for (size_t cut = 0; cut <= 9; cut++) {
        uint32_t c = proto_crc32_update(0, s, cut);
        c = proto_crc32_update(c, s + cut, 9 - cut);
        assert_int_equal(c, 0xCBF43926u);
    }
}

static void test_encode_layout_is_little_endian_with_crc(void **state)
{
    (void)state;
    uint8_t out[64];
    size_t sz;
    const uint8_t pl[3] = {0xaa, 0xbb, 0xcc};
    assert_int_equal(proto_fsp_encode(PROTO_FSP_SCAN_DONE, 0x1234, pl, 3, out,
                                      sizeof out, &sz),
                     0);
    assert_int_equal(sz, 19);
    const uint8_t head[12] = {'F', 'S', 'P', '1', 0x85, 0,
                              0x34, 0x12, 3, 0, 0, 0};
    assert_memory_equal(out, head, 12);
    assert_memory_equal(out + 12, pl, 3);
    uint32_t crc = proto_crc32(out, 15);
    assert_int_equal(out[15], crc & 0xff);
    assert_int_equal(out[18], crc >> 24);
    /* the HELLO example of proto/FSP1.md */
    const char *hello = "{\"host\":\"facetd\",\"version\":\"0.1.0\"}";
    assert_int_equal(proto_fsp_encode(PROTO_FSP_HELLO, 0, hello,
                                      strlen(hello), out, sizeof out, &sz),
                     0);
    assert_int_equal(sz, 51);
    assert_int_equal(proto_crc32(out, 47), 0x989c29edu);
}

static void test_encode_rejects_oversize_and_short_buffer(void **state)
{
    (void)state;
    size_t sz = 99;
    uint8_t small[20];
    assert_int_equal(proto_fsp_encode(1, 0, NULL, PROTO_FSP_MAX_PAYLOAD + 1,
                                      small, sizeof small, &sz),
                     -EMSGSIZE);
    uint8_t pl[5] = {0};
    assert_int_equal(proto_fsp_encode(1, 0, pl, 5, small, sizeof small, &sz),
                     -ENOBUFS);
    assert_int_equal(sz, 99);
}

static void test_decode_every_two_piece_split(void **state)
{
    (void)state;
    static uint8_t buf[8192];
    log expect = {0};
    size_t n = sample_stream(buf, sizeof buf, &expect);
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    for (size_t cut = 0; cut <= n; cut++) {
        log got = {0};
        proto_fsp_decoder_reset(d);
        feed_cuts(d, buf, n, &cut, 1, &got);
        assert_logs_equal(&got, &expect);
    }
    proto_fsp_decoder_free(d);
}

static void test_decode_byte_by_byte_and_random_splits(void **state)
{
    (void)state;
    static uint8_t buf[8192];
    log expect = {0};
    size_t n = sample_stream(buf, sizeof buf, &expect);
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    static size_t cuts[8192];
    for (size_t i = 1; i < n; i++)
        cuts[i - 1] = i;
    log got = {0};
    feed_cuts(d, buf, n, cuts, n - 1, &got);
    assert_logs_equal(&got, &expect);
    uint64_t rng = 42;
    for (int round = 0; round < 300; round++) {
        size_t k = 1 + geo_rand_next(&rng) % 12, m = 0;
        for (size_t i = 0; i < k; i++)
            cuts[m++] = geo_rand_next(&rng) % (n + 1);
        /* sort the cut positions */
        for (size_t i = 1; i < m; i++)
            for (size_t j = i; j > 0 && cuts[j - 1] > cuts[j]; j--) {
                size_t t = cuts[j];
                cuts[j] = cuts[j - 1];
                cuts[j - 1] = t;
            }
        memset(&got, 0, sizeof got);
        proto_fsp_decoder_reset(d);
        feed_cuts(d, buf, n, cuts, m, &got);
        assert_logs_equal(&got, &expect);
    }
    proto_fsp_decoder_free(d);
}

static void test_garbage_before_frames_is_one_bad_magic_event(void **state)
{
    (void)state;
    static uint8_t buf[9000];
    const char junk[] = "xxFSPFFSP0garbage FS";
    size_t j = sizeof junk - 1;
    memcpy(buf, junk, j);
    log expect = {0};
    expect.ev[expect.n++].kind = PROTO_FSP_EV_BAD_MAGIC;
    size_t n = j + sample_stream(buf + j, sizeof buf - j, &expect);
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    for (size_t cut = 0; cut <= n; cut += 7) {
        log got = {0};
        proto_fsp_decoder_reset(d);
        feed_cuts(d, buf, n, &cut, 1, &got);
        assert_logs_equal(&got, &expect);
    }
    proto_fsp_decoder_free(d);
}

static void test_bad_crc_reports_once_and_next_frames_survive(void **state)
{
    (void)state;
    static uint8_t buf[8192];
    log expect = {0};
    size_t n = sample_stream(buf, sizeof buf, &expect);
    /* corrupt one payload byte of the third frame (MODEL, seq 2) */
    size_t off3 = 2 * PROTO_FSP_OVERHEAD + strlen(
        "{\"host\":\"facetd\",\"version\":\"0.1.0\"}");
    buf[off3 + PROTO_FSP_HEADER_SIZE + 100] ^= 0x40;
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    log got = {0};
    feed_all(d, buf, n, &got);
    assert_int_equal(got.n, 5);
    assert_int_equal(got.ev[2].kind, PROTO_FSP_EV_BAD_CRC);
    assert_int_equal(got.ev[2].seq, 2);
    assert_int_equal(got.ev[2].type, PROTO_FSP_MODEL);
    expect.ev[2] = got.ev[2];
    assert_logs_equal(&got, &expect);
    proto_fsp_decoder_free(d);
}

static void test_corrupt_length_does_not_hide_following_frames(void **state)
{
    (void)state;
    static uint8_t buf[8192];
    log expect = {0};
    size_t n = sample_stream(buf, sizeof buf, &expect);
    /* the first frame claims 60000 payload bytes: more than the stream */
    buf[8] = 0x60;
    buf[9] = 0xea;
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    log got = {0};
    feed_all(d, buf, n, &got);
    /* nothing can be decided yet: the decoder waits for 60000 bytes */
    assert_int_equal(got.n, 0);
    /* the rest of the 60000 bytes arrive (zeros), the CRC fails, and the
     * rescan finds the four frames that were buffered behind it */
    static uint8_t zeros[60000];
    feed_all(d, zeros, sizeof zeros, &got);
    assert_true(got.n >= 5);
    assert_int_equal(got.ev[0].kind, PROTO_FSP_EV_BAD_CRC);
    for (size_t i = 1; i < 5; i++) {
        assert_int_equal(got.ev[i].kind, PROTO_FSP_EV_FRAME);
        assert_int_equal(got.ev[i].seq, expect.ev[i].seq);
        assert_int_equal(got.ev[i].crc, expect.ev[i].crc);
    }
    proto_fsp_decoder_free(d);
}

static void test_payload_limit(void **state)
{
    (void)state;
    static uint8_t buf[2 * PROTO_FSP_MAX_FRAME];
    static uint8_t pl[PROTO_FSP_MAX_PAYLOAD];
    memset(pl, 0x5a, sizeof pl);
    size_t n = 0;
    put_frame(buf, sizeof buf, &n, PROTO_FSP_RESULT, 9, pl, sizeof pl);
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    log got = {0};
    feed_all(d, buf, n, &got);
    assert_int_equal(got.n, 1);
    assert_int_equal(got.ev[0].kind, PROTO_FSP_EV_FRAME);
    assert_int_equal(got.ev[0].len, PROTO_FSP_MAX_PAYLOAD);
    proto_fsp_decoder_free(d);

    /* a decoder limited to 100 bytes rejects 101 and keeps going */
    n = 0;
    put_frame(buf, sizeof buf, &n, PROTO_FSP_RESULT, 1, pl, 101);
    put_frame(buf, sizeof buf, &n, PROTO_FSP_RESULT, 2, pl, 100);
    d = proto_fsp_decoder_new(100);
    memset(&got, 0, sizeof got);
    feed_all(d, buf, n, &got);
    assert_int_equal(got.n, 2);
    assert_int_equal(got.ev[0].kind, PROTO_FSP_EV_TOO_LONG);
    assert_int_equal(got.ev[0].len, 101);
    assert_int_equal(got.ev[1].kind, PROTO_FSP_EV_FRAME);
    assert_int_equal(got.ev[1].seq, 2);
    assert_true(proto_fsp_decoder_skipped(d) >= 117);
    proto_fsp_decoder_free(d);

    /* a header claiming 65537 bytes is rejected by the default decoder */
    uint8_t hdr[12] = {'F', 'S', 'P', '1', 7, 0, 0, 0, 1, 0, 1, 0};
    d = proto_fsp_decoder_new(0);
    memset(&got, 0, sizeof got);
    feed_all(d, hdr, sizeof hdr, &got);
    assert_int_equal(got.n, 1);
    assert_int_equal(got.ev[0].kind, PROTO_FSP_EV_TOO_LONG);
    proto_fsp_decoder_free(d);
}

static proto_fsp_frame frame_of(uint8_t type, const void *p, size_t len)
{
    proto_fsp_frame f = {.type = type, .len = (uint32_t)len, .payload = p};
    return f;
}

static void test_fixed_payloads_round_trip_and_reject_bad_lengths(void **state)
{
    (void)state;
    geo_err err;
    uint8_t b[16];
    uint16_t seq;
    size_t n = proto_fsp_build_seq(b, 0xbeef);
    proto_fsp_frame f = frame_of(PROTO_FSP_NAK, b, n);
    assert_int_equal(proto_fsp_parse_seq(&f, &seq, &err), 0);
    assert_int_equal(seq, 0xbeef);
    f.len = 3;
    assert_int_equal(proto_fsp_parse_seq(&f, &seq, &err), -EINVAL);
    f = frame_of(PROTO_FSP_MODEL, b, 2);
    assert_int_equal(proto_fsp_parse_seq(&f, &seq, &err), -EINVAL);

    proto_fsp_scan_started ss = {2, 400}, ss2;
    f = frame_of(PROTO_FSP_SCAN_STARTED, b,
                 proto_fsp_build_scan_started(b, &ss));
    assert_int_equal(proto_fsp_parse_scan_started(&f, &ss2, &err), 0);
    assert_int_equal(ss2.mode, 2);
    assert_int_equal(ss2.contours, 400);
    b[0] = 3;
    assert_int_equal(proto_fsp_parse_scan_started(&f, &ss2, &err), -EINVAL);

    proto_fsp_progress pg = {10, 400}, pg2;
    f = frame_of(PROTO_FSP_PROGRESS, b, proto_fsp_build_progress(b, &pg));
    assert_int_equal(proto_fsp_parse_progress(&f, &pg2, &err), 0);
    assert_int_equal(pg2.done, 10);
    pg.done = 401;
    proto_fsp_build_progress(b, &pg);
    assert_int_equal(proto_fsp_parse_progress(&f, &pg2, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "PROGRESS"));

    proto_fsp_scan_done sd = {1000, 0xdeadbeef, 1}, sd2;
    f = frame_of(PROTO_FSP_SCAN_DONE, b, proto_fsp_build_scan_done(b, &sd));
    assert_int_equal(f.len, 9);
    assert_int_equal(proto_fsp_parse_scan_done(&f, &sd2, &err), 0);
    assert_int_equal(sd2.crc, 0xdeadbeef);
    assert_int_equal(sd2.format, 1);
    b[8] = 2;
    assert_int_equal(proto_fsp_parse_scan_done(&f, &sd2, &err), -EINVAL);
    f.len = 10;
    assert_int_equal(proto_fsp_parse_scan_done(&f, &sd2, &err), -EINVAL);

    uint8_t mode;
    f = frame_of(PROTO_FSP_START_SCAN, b, proto_fsp_build_start_scan(b, 1));
    assert_int_equal(proto_fsp_parse_start_scan(&f, &mode, &err), 0);
    assert_int_equal(mode, 1);
}

static void test_model_chunk_checks_bounds(void **state)
{
    (void)state;
    geo_err err;
    static uint8_t b[8 + PROTO_FSP_MODEL_CHUNK_MAX + 1];
    static uint8_t model[PROTO_FSP_MODEL_CHUNK_MAX + 1];
    proto_fsp_model_chunk c;
    size_t n = proto_fsp_build_model(b, 1000, 900, model, 100);
    proto_fsp_frame f = frame_of(PROTO_FSP_MODEL, b, n);
    assert_int_equal(proto_fsp_parse_model(&f, &c, &err), 0);
    assert_int_equal(c.offset, 900);
    assert_int_equal(c.len, 100);
    assert_ptr_equal(c.bytes, b + 8);
    /* one byte beyond the total */
    n = proto_fsp_build_model(b, 1000, 901, model, 100);
    f = frame_of(PROTO_FSP_MODEL, b, n);
    assert_int_equal(proto_fsp_parse_model(&f, &c, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "beyond total"));
    /* offset overflow must not wrap */
    n = proto_fsp_build_model(b, 1000, 0xffffffffu, model, 10);
    f = frame_of(PROTO_FSP_MODEL, b, n);
    assert_int_equal(proto_fsp_parse_model(&f, &c, &err), -EINVAL);
    /* an empty chunk and an oversized chunk */
    f = frame_of(PROTO_FSP_MODEL, b, 8);
    assert_int_equal(proto_fsp_parse_model(&f, &c, &err), -EINVAL);
    n = proto_fsp_build_model(b, 100000, 0, model,
                              PROTO_FSP_MODEL_CHUNK_MAX + 1);
    f = frame_of(PROTO_FSP_MODEL, b, n);
    assert_int_equal(proto_fsp_parse_model(&f, &c, &err), -EINVAL);
}

static void test_error_payload_keeps_utf8_whole(void **state)
{
    (void)state;
    geo_err err;
    uint8_t b[16];
    /* "Ошибка" is two bytes per letter; 16 - 2 = 14 bytes hold 7 letters */
    size_t n = proto_fsp_build_error(b, sizeof b, 3, "Ошибка сканера");
    assert_int_equal(n, 2 + 12 + 1 + 0);
    proto_fsp_frame f = frame_of(PROTO_FSP_ERROR, b, n);
    uint16_t code;
    char msg[8];
    assert_int_equal(proto_fsp_parse_error(&f, &code, msg, sizeof msg, &err),
                     0);
    assert_int_equal(code, 3);
    assert_string_equal(msg, "Оши"); /* 7 bytes room: 3 letters */
    b[3] = 0xff;
    assert_int_equal(proto_fsp_parse_error(&f, &code, msg, sizeof msg, &err),
                     -EINVAL);
    uint8_t nul[4] = {1, 0, 'a', 0};
    f = frame_of(PROTO_FSP_ERROR, nul, 4);
    assert_int_equal(proto_fsp_parse_error(&f, &code, NULL, 0, &err), -EINVAL);
}

static void test_json_payloads_round_trip_and_are_strict(void **state)
{
    (void)state;
    geo_err err;
    proto_fsp_info in = {"Acme", "Shadow-3", "SN-0001", "1.2.3", 400}, out;
    char *s = proto_fsp_build_info(&in);
    assert_non_null(s);
    proto_fsp_frame f = frame_of(PROTO_FSP_INFO, s, strlen(s));
    assert_int_equal(proto_fsp_parse_info(&f, &out, &err), 0);
    assert_string_equal(out.serial, "SN-0001");
    assert_string_equal(out.firmware, "1.2.3");
    assert_int_equal(out.contours, 400);
    free(s);

    const char *bad[] = {
        "{\"vendor\":\"a\",\"model\":\"b\",\"serial\":\"x y\","
        "\"firmware\":\"1\",\"contours\":1}",
        "{\"vendor\":\"a\",\"model\":\"b\",\"serial\":\"s\","
        "\"firmware\":\"1\",\"contours\":-1}",
        "{\"vendor\":\"a\",\"vendor\":\"a\",\"model\":\"b\",\"serial\":\"s\","
        "\"firmware\":\"1\",\"contours\":1}",
        "{\"vendor\":\"a\",\"model\":\"b\",\"serial\":\"s\",\"contours\":1}",
        "[1,2]",
        "{\"vendor\":\"a\",",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        f = frame_of(PROTO_FSP_INFO, bad[i], strlen(bad[i]));
        assert_int_equal(proto_fsp_parse_info(&f, &out, &err), -EINVAL);
        assert_non_null(strstr(err.msg, "INFO"));
    }
    strcpy(in.serial, "bad/serial");
    assert_null(proto_fsp_build_info(&in));

    proto_fsp_result r = {"j-42", "succeeded", "/v1/jobs/j-42", 900, 57,
                          0, true},
                     r2;
    s = proto_fsp_build_result(&r);
    f = frame_of(PROTO_FSP_RESULT, s, strlen(s));
    assert_int_equal(proto_fsp_parse_result(&f, &r2, &err), 0);
    assert_string_equal(r2.url, "/v1/jobs/j-42");
    assert_int_equal(r2.facets_after, 57);
    assert_true(r2.valid);
    free(s);
    r.facets_after = -1;
    r.valid = false;
    s = proto_fsp_build_result(&r);
    assert_non_null(strstr(s, "\"facets_after\":null"));
    f = frame_of(PROTO_FSP_RESULT, s, strlen(s));
    assert_int_equal(proto_fsp_parse_result(&f, &r2, &err), 0);
    assert_int_equal(r2.facets_after, -1);
    free(s);

    proto_fsp_hello h = {"facetd", "0.1.0"}, h2;
    s = proto_fsp_build_hello(&h);
    assert_string_equal(s, "{\"host\":\"facetd\",\"version\":\"0.1.0\"}");
    f = frame_of(PROTO_FSP_HELLO, s, strlen(s));
    assert_int_equal(proto_fsp_parse_hello(&f, &h2, &err), 0);
    assert_string_equal(h2.version, "0.1.0");
    free(s);
}

static void test_type_names(void **state)
{
    (void)state;
    assert_string_equal(proto_fsp_type_name(PROTO_FSP_SCAN_DONE), "SCAN_DONE");
    assert_true(proto_fsp_type_known(PROTO_FSP_ERROR));
    assert_false(proto_fsp_type_known(0x08));
    assert_false(proto_fsp_type_known(0x80));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32_check_value_and_incremental),
        cmocka_unit_test(test_encode_layout_is_little_endian_with_crc),
        cmocka_unit_test(test_encode_rejects_oversize_and_short_buffer),
        cmocka_unit_test(test_decode_every_two_piece_split),
        cmocka_unit_test(test_decode_byte_by_byte_and_random_splits),
        cmocka_unit_test(test_garbage_before_frames_is_one_bad_magic_event),
        cmocka_unit_test(test_bad_crc_reports_once_and_next_frames_survive),
        cmocka_unit_test(test_corrupt_length_does_not_hide_following_frames),
        cmocka_unit_test(test_payload_limit),
        cmocka_unit_test(test_fixed_payloads_round_trip_and_reject_bad_lengths),
        cmocka_unit_test(test_model_chunk_checks_bounds),
        cmocka_unit_test(test_error_payload_keeps_utf8_whole),
        cmocka_unit_test(test_json_payloads_round_trip_and_are_strict),
        cmocka_unit_test(test_type_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
