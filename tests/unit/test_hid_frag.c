/* test_hid_frag.c — HID fragmentation of FSP/1 frames: the report layout,
 * round trips for every length around report boundaries and at the
 * largest frame, and each reassembly failure (middle fragment without a
 * first, overlong frame, bad lengths, bad reports, restarts). */
#include "testutil.h"

#include <string.h>

#include "fsp.h"
#include "hid_frag.h"

static void fill(uint8_t *b, size_t n, uint8_t seed)
{
    for (size_t i = 0; i < n; i++)
        b[i] = (uint8_t)(seed + i * 13);
}

static void test_report_layout(void **state)
{
    (void)state;
    uint8_t frame[100], rep[64];
    fill(frame, sizeof frame, 1);
    assert_int_equal(proto_hid_report_count(100), 2);
    assert_int_equal(proto_hid_report_count(61), 1);
    assert_int_equal(proto_hid_report_count(62), 2);
    assert_int_equal(proto_hid_report_count(0), 0);
    proto_hid_fragment(frame, 100, 0, rep);
    assert_int_equal(rep[0], 1);
    assert_int_equal(rep[1], PROTO_HID_FIRST);
    assert_int_equal(rep[2], 61);
    assert_memory_equal(rep + 3, frame, 61);
    proto_hid_fragment(frame, 100, 1, rep);
    assert_int_equal(rep[1], PROTO_HID_LAST);
    assert_int_equal(rep[2], 39);
    assert_memory_equal(rep + 3, frame + 61, 39);
    for (size_t i = 3 + 39; i < 64; i++)
        assert_int_equal(rep[i], 0);
    proto_hid_fragment(frame, 16, 0, rep);
    assert_int_equal(rep[1], PROTO_HID_FIRST | PROTO_HID_LAST);
}

static void round_trip(proto_hid_reasm *r, const uint8_t *frame, size_t len)
{
    size_t count = proto_hid_report_count(len);
    uint8_t rep[64];
    for (size_t k = 0; k < count; k++) {
        proto_hid_fragment(frame, len, k, rep);
        const uint8_t *out = NULL;
        size_t out_len = 0;
        proto_hid_status st = proto_hid_reasm_push(r, rep, 64, &out, &out_len);
        if (k + 1 < count) {
            assert_int_equal(st, PROTO_HID_MORE);
        } else {
            assert_int_equal(st, PROTO_HID_FRAME);
            assert_int_equal(out_len, len);
            assert_memory_equal(out, frame, len);
        }
    }
}

static void test_round_trip_every_length_near_boundaries(void **state)
{
    (void)state;
    static uint8_t frame[PROTO_FSP_MAX_FRAME];
    fill(frame, sizeof frame, 7);
    proto_hid_reasm *r = proto_hid_reasm_new(0);
    for (size_t len = 1; len <= 4 * 61 + 2; len++)
        round_trip(r, frame, len);
    round_trip(r, frame, PROTO_FSP_MAX_FRAME);
    proto_hid_reasm_free(r);
}

static void test_middle_fragment_without_first_is_rejected(void **state)
{
    (void)state;
    uint8_t frame[200], rep[64];
    fill(frame, sizeof frame, 3);
    proto_hid_reasm *r = proto_hid_reasm_new(0);
    const uint8_t *out;
    size_t n;
    proto_hid_fragment(frame, 200, 1, rep); /* a middle fragment */
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_NO_FIRST);
    proto_hid_fragment(frame, 200, 3, rep); /* the last one */
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_NO_FIRST);
    /* the next whole frame still goes through */
    round_trip(r, frame, 200);
    proto_hid_reasm_free(r);
}

static void test_overlong_frame_is_dropped(void **state)
{
    (void)state;
    uint8_t frame[400], rep[64];
    fill(frame, sizeof frame, 5);
    proto_hid_reasm *r = proto_hid_reasm_new(150);
    const uint8_t *out;
    size_t n;
    proto_hid_status st = PROTO_HID_MORE;
    size_t k = 0;
    for (; k < proto_hid_report_count(400) && st == PROTO_HID_MORE; k++) {
        proto_hid_fragment(frame, 400, k, rep);
        st = proto_hid_reasm_push(r, rep, 64, &out, &n);
    }
    assert_int_equal(st, PROTO_HID_E_OVERLONG);
    assert_int_equal(k, 3); /* 61 + 61 fit in 150, the third does not */
    /* the rest of that frame has no first fragment any more */
    proto_hid_fragment(frame, 400, k, rep);
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_NO_FIRST);
    round_trip(r, frame, 150);
    proto_hid_reasm_free(r);
}

static void test_bad_lengths_and_reports(void **state)
{
    (void)state;
    uint8_t frame[50], rep[64];
    fill(frame, sizeof frame, 9);
    proto_hid_reasm *r = proto_hid_reasm_new(0);
    const uint8_t *out;
    size_t n;
    proto_hid_fragment(frame, 50, 0, rep);
    rep[2] = 62;
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_LENGTH);
    rep[2] = 0;
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_LENGTH);
    proto_hid_fragment(frame, 50, 0, rep);
    assert_int_equal(proto_hid_reasm_push(r, rep, 63, &out, &n),
                     PROTO_HID_E_REPORT);
    rep[0] = 2;
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_REPORT);
    proto_hid_fragment(frame, 50, 0, rep);
    rep[63] = 1; /* padding must be zero */
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_REPORT);
    proto_hid_fragment(frame, 50, 0, rep);
    rep[1] |= 0x80;
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_REPORT);
    round_trip(r, frame, 50);
    proto_hid_reasm_free(r);
}

static void test_first_fragment_mid_frame_restarts(void **state)
{
    (void)state;
    uint8_t a[200], b[30], rep[64];
    fill(a, sizeof a, 1);
    fill(b, sizeof b, 2);
    proto_hid_reasm *r = proto_hid_reasm_new(0);
    const uint8_t *out;
    size_t n;
    proto_hid_fragment(a, 200, 0, rep);
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_MORE);
    /* a one-report frame interrupts: restart reported, frame delivered */
    proto_hid_fragment(b, 30, 0, rep);
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_RESTART);
    assert_non_null(out);
    assert_int_equal(n, 30);
    assert_memory_equal(out, b, 30);
    /* a multi-report frame interrupts: restart, then it completes */
    proto_hid_fragment(a, 200, 0, rep);
    proto_hid_reasm_push(r, rep, 64, &out, &n);
    proto_hid_fragment(a, 200, 0, rep);
    assert_int_equal(proto_hid_reasm_push(r, rep, 64, &out, &n),
                     PROTO_HID_E_RESTART);
    assert_null(out);
    for (size_t k = 1; k < 4; k++) {
        proto_hid_fragment(a, 200, k, rep);
        proto_hid_status st = proto_hid_reasm_push(r, rep, 64, &out, &n);
        assert_int_equal(st, k == 3 ? PROTO_HID_FRAME : PROTO_HID_MORE);
    }
    assert_memory_equal(out, a, 200);
    proto_hid_reasm_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_report_layout),
        cmocka_unit_test(test_round_trip_every_length_near_boundaries),
        cmocka_unit_test(test_middle_fragment_without_first_is_rejected),
        cmocka_unit_test(test_overlong_frame_is_dropped),
        cmocka_unit_test(test_bad_lengths_and_reports),
        cmocka_unit_test(test_first_fragment_mid_frame_restarts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
