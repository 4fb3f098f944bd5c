/* test_session.c — the host side of an FSP/1 session over the in-memory
 * transport with a fake clock: greeting, a whole 400-contour scan split
 * into arbitrary reads, NAK and re-send of a corrupted or missing MODEL
 * frame, the whole-model CRC (three NAKs then drop), the 30 s timeout,
 * bounded NAK retries, HELLO mid-scan, duplicates, out-of-order chunks,
 * RESULT re-sends and device NAKs of host frames, and a SCAN_DONE whose
 * ACK waits for the caller to keep the scan. */
#include "testutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crc32.h"
#include "fsp.h"
#include "mem_transport.h"
#include "session.h"

typedef struct env {
    uint64_t clock;
    scan_transport *t;
    scan_session *s;
    uint16_t dseq; /* the device's next sequence number */
    /* events seen */
    int infos, started, progress, completed, dropped, errors;
    uint8_t *model;
    size_t model_len;
    uint8_t format;
    char why[128];
} env;

static void ev_info(void *u, const proto_fsp_info *i)
{
    (void)i;
    ((env *)u)->infos++;
}

static void ev_started(void *u, uint8_t mode, uint32_t contours)
{
    (void)mode;
    (void)contours;
    ((env *)u)->started++;
}

static void ev_progress(void *u, uint32_t done, uint32_t total)
{
    (void)done;
    (void)total;
    ((env *)u)->progress++;
}

static void ev_complete(void *u, uint8_t *bytes, size_t len, uint8_t format)
{
    env *e = u;
    e->completed++;
    free(e->model);
    e->model = bytes;
    e->model_len = len;
    e->format = format;
}

static void ev_dropped(void *u, const char *why)
{
    env *e = u;
    e->dropped++;
    snprintf(e->why, sizeof e->why, "%s", why);
}

static void ev_error(void *u, uint16_t code, const char *msg)
{
    (void)code;
    (void)msg;
    ((env *)u)->errors++;
}

static env *env_new_cfg(size_t chunk, const scan_session_cfg *cfg)
{
    env *e = calloc(1, sizeof *e);
    e->clock = 1000;
    e->t = mem_transport_new(&e->clock, chunk);
    scan_session_events ev = {e,           ev_info,    ev_started,
                              ev_progress, ev_complete, ev_dropped,
                              ev_error};
    e->s = scan_session_new(cfg, &ev);
    return e;
}

static env *env_new(size_t chunk)
{
    return env_new_cfg(chunk, NULL);
}

static void env_free(env *e)
{
    scan_session_free(e->s);
    e->t->ops->close(e->t);
    free(e->model);
    free(e);
}

/* Delivers everything pushed so far, then runs timers and sends. */
static void pump(env *e)
{
    static uint8_t buf[PROTO_FSP_MAX_FRAME];
    ssize_t n;
    while ((n = e->t->ops->read(e->t, buf, sizeof buf, 0)) > 0)
        scan_session_input(e->s, buf, (size_t)n, e->clock);
    scan_session_tick(e->s, e->clock);
    assert_int_equal(scan_session_flush(e->s, e->t, 0), 0);
}

/* Lets ms milliseconds pass in steps, pumping at each. */
static void wait_ms(env *e, uint64_t ms)
{
    uint64_t end = e->clock + ms;
    while (e->clock < end) {
        uint64_t d = scan_session_deadline(e->s);
        uint64_t next = d < end ? d : end;
        e->clock = next > e->clock ? next : e->clock + 1;
        pump(e);
    }
}

static uint16_t dev(env *e, uint8_t type, const void *p, size_t len,
                    int corrupt)
{
    uint16_t seq = e->dseq++;
    mem_transport_push_frame(e->t, type, seq, p, len, corrupt);
    return seq;
}

static void greet(env *e)
{
    assert_int_equal(scan_session_hello(e->s, e->clock), 0);
    pump(e);
    const mem_frame *h = mem_transport_sent(e->t, 0);
    assert_int_equal(h->type, PROTO_FSP_HELLO);
    assert_int_equal(h->seq, 0);
    proto_fsp_info in = {"Acme", "Shadow", "SN-1", "1.0", 400};
    char *js = proto_fsp_build_info(&in);
    e->dseq = 0;
    dev(e, PROTO_FSP_INFO, js, strlen(js), 0);
    free(js);
    pump(e);
    assert_true(scan_session_ready(e->s));
    assert_int_equal(e->infos, 1);
}

static uint8_t *load_model(size_t *len)
{
    FILE *f = fopen(tu_model_path("brilliant.scan-k400.json"), "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)n);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

static uint16_t model_frame(env *e, const uint8_t *m, size_t total,
                            size_t off, int corrupt)
{
    static uint8_t p[8 + PROTO_FSP_MODEL_CHUNK_MAX];
    size_t n = total - off < PROTO_FSP_MODEL_CHUNK_MAX
                   ? total - off
                   : PROTO_FSP_MODEL_CHUNK_MAX;
    size_t pl = proto_fsp_build_model(p, (uint32_t)total, (uint32_t)off,
                                      m + off, (uint32_t)n);
    return dev(e, PROTO_FSP_MODEL, p, pl, corrupt);
}

static uint16_t scan_done(env *e, const uint8_t *m, size_t total, int bad)
{
    proto_fsp_scan_done d = {(uint32_t)total,
                             proto_crc32(m, total) ^ (bad ? 1u : 0u), 0};
    uint8_t p[9];
    return dev(e, PROTO_FSP_SCAN_DONE, p, proto_fsp_build_scan_done(p, &d), 0);
}

static void scan_started(env *e)
{
    proto_fsp_scan_started ss = {1, 400};
    uint8_t p[5];
    dev(e, PROTO_FSP_SCAN_STARTED, p, proto_fsp_build_scan_started(p, &ss), 0);
}

static bool acked(env *e, uint16_t seq, size_t from)
{
    for (size_t i = from; i < mem_transport_sent_count(e->t); i++) {
        const mem_frame *f = mem_transport_sent(e->t, i);
        if (f->type == PROTO_FSP_ACK && f->len == 2 &&
            (f->payload[0] | f->payload[1] << 8) == seq)
            return true;
    }
    return false;
}

static size_t naks_of(env *e, uint16_t seq, size_t from)
{
    size_t c = 0;
    for (size_t i = from; i < mem_transport_sent_count(e->t); i++) {
        const mem_frame *f = mem_transport_sent(e->t, i);
        c += f->type == PROTO_FSP_NAK &&
             (f->payload[0] | f->payload[1] << 8) == seq;
    }
    return c;
}

static void test_frames_before_info_are_ignored_and_get_info_repeats(
    void **state)
{
    (void)state;
    env *e = env_new(0);
    scan_session_hello(e->s, e->clock);
    pump(e);
    /* an earlier session's frame still in flight */
    scan_started(e);
    pump(e);
    assert_int_equal(e->started, 0);
    assert_int_equal(scan_session_get_stats(e->s)->ignored, 1);
    assert_int_equal(scan_session_start_scan(e->s, 0, e->clock), -EAGAIN);
    wait_ms(e, 4500);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_GET_INFO, 0), 2);
    env_free(e);
}

static void test_whole_scan_in_small_reads(void **state)
{
    (void)state;
    env *e = env_new(7);
    greet(e);
    size_t total;
    uint8_t *m = load_model(&total);
    scan_started(e);
    proto_fsp_progress pg = {400, 400};
    uint8_t p[8];
    dev(e, PROTO_FSP_PROGRESS, p, proto_fsp_build_progress(p, &pg), 0);
    size_t from = mem_transport_sent_count(e->t);
    uint16_t first = e->dseq;
    for (size_t off = 0; off < total; off += PROTO_FSP_MODEL_CHUNK_MAX)
        model_frame(e, m, total, off, 0);
    uint16_t done = scan_done(e, m, total, 0);
    pump(e);
    for (uint16_t q = first; q != done; q++)
        assert_true(acked(e, q, from));
    assert_true(acked(e, done, from));
    assert_int_equal(e->completed, 1);
    assert_int_equal(e->model_len, total);
    assert_memory_equal(e->model, m, total);
    assert_int_equal(e->format, PROTO_FSP_MODEL_JSON);
    assert_int_equal(e->progress, 1);
    const scan_session_stats *st = scan_session_get_stats(e->s);
    assert_int_equal(st->scans_completed, 1);
    assert_int_equal(st->naks_sent, 0);
    assert_int_equal(st->model_bytes, total);
    assert_false(scan_session_scanning(e->s, NULL, NULL));
    free(m);
    env_free(e);
}

static void test_corrupted_model_frame_is_naked_and_resent(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    size_t total;
    uint8_t *m = load_model(&total);
    scan_started(e);
    size_t from = mem_transport_sent_count(e->t);
    model_frame(e, m, total, 0, 0);
    uint16_t bad = model_frame(e, m, total, PROTO_FSP_MODEL_CHUNK_MAX, 1);
    pump(e);
    assert_int_equal(naks_of(e, bad, from), 1);
    assert_false(acked(e, bad, from));
    assert_int_equal(scan_session_get_stats(e->s)->crc_errors, 1);
    /* the device sends it again with its original number, then the rest */
    uint16_t save = e->dseq;
    e->dseq = bad;
    model_frame(e, m, total, PROTO_FSP_MODEL_CHUNK_MAX, 0);
    e->dseq = save;
    for (size_t off = 2 * PROTO_FSP_MODEL_CHUNK_MAX; off < total;
         off += PROTO_FSP_MODEL_CHUNK_MAX)
        model_frame(e, m, total, off, 0);
    uint16_t done = scan_done(e, m, total, 0);
    pump(e);
    assert_true(acked(e, bad, from));
    assert_true(acked(e, done, from));
    assert_int_equal(e->completed, 1);
    assert_memory_equal(e->model, m, total);
    free(m);
    env_free(e);
}

static void test_missing_frame_holds_scan_done_until_resent(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    size_t total;
    uint8_t *m = load_model(&total);
    scan_started(e);
    size_t from = mem_transport_sent_count(e->t);
    uint16_t lost = 0;
    for (size_t off = 0; off < total; off += PROTO_FSP_MODEL_CHUNK_MAX) {
        if (off == 3 * PROTO_FSP_MODEL_CHUNK_MAX)
            lost = e->dseq++; /* never arrives */
        else
            model_frame(e, m, total, off, 0);
    }
    uint16_t done = scan_done(e, m, total, 0);
    pump(e);
    assert_int_equal(naks_of(e, lost, from), 1);
    assert_false(acked(e, done, from));
    assert_int_equal(e->completed, 0);
    /* nothing arrives for 5 s: the host asks again */
    wait_ms(e, 5000);
    assert_int_equal(naks_of(e, lost, from), 2);
    uint16_t save = e->dseq;
    e->dseq = lost;
    model_frame(e, m, total, 3 * PROTO_FSP_MODEL_CHUNK_MAX, 0);
    e->dseq = save;
    pump(e);
    assert_true(acked(e, lost, from));
    assert_true(acked(e, done, from));
    assert_int_equal(e->completed, 1);
    assert_memory_equal(e->model, m, total);
    free(m);
    env_free(e);
}

static void test_wrong_model_crc_is_naked_three_times_then_dropped(
    void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    uint8_t m[100];
    memset(m, 'x', sizeof m);
    scan_started(e);
    size_t from = mem_transport_sent_count(e->t);
    model_frame(e, m, sizeof m, 0, 0);
    uint16_t done = scan_done(e, m, sizeof m, 1);
    pump(e);
    assert_int_equal(naks_of(e, done, from), 1);
    for (int i = 0; i < 2; i++) {
        uint16_t save = e->dseq;
        e->dseq = done;
        scan_done(e, m, sizeof m, 1);
        e->dseq = save;
        pump(e);
    }
    assert_int_equal(naks_of(e, done, from), 3);
    assert_false(acked(e, done, from));
    assert_int_equal(e->dropped, 1);
    assert_int_equal(e->completed, 0);
    assert_false(scan_session_scanning(e->s, NULL, NULL));
    /* the device's ERROR 3 that follows does not count twice */
    uint8_t p[32];
    dev(e, PROTO_FSP_ERROR, p,
        proto_fsp_build_error(p, sizeof p, PROTO_FSP_ERR_SCAN_DROPPED,
                              "scan dropped"),
        0);
    pump(e);
    assert_int_equal(e->errors, 1);
    assert_int_equal(scan_session_get_stats(e->s)->scans_dropped, 1);
    env_free(e);
}

static void test_scan_given_up_after_30s_without_a_frame(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    static uint8_t m[50000];
    scan_started(e);
    model_frame(e, m, sizeof m, 0, 0);
    pump(e);
    size_t from = mem_transport_sent_count(e->t);
    wait_ms(e, 29000);
    assert_int_equal(e->dropped, 0);
    assert_true(scan_session_scanning(e->s, NULL, NULL));
    wait_ms(e, 1000);
    assert_int_equal(e->dropped, 1);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_ABORT, from), 1);
    assert_false(scan_session_scanning(e->s, NULL, NULL));
    env_free(e);
}

static void test_chunk_outside_total_is_naked_then_scan_dropped(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    scan_started(e);
    size_t from = mem_transport_sent_count(e->t);
    uint8_t p[8 + 10];
    uint8_t bytes[10] = {0};
    size_t pl = proto_fsp_build_model(p, 100, 95, bytes, 10);
    uint16_t seq = e->dseq;
    for (int i = 0; i < 6; i++) {
        e->dseq = seq;
        dev(e, PROTO_FSP_MODEL, p, pl, 0);
        pump(e);
    }
    assert_int_equal(naks_of(e, seq, from), 5);
    assert_int_equal(e->dropped, 1);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_ABORT, from), 1);
    assert_true(scan_session_get_stats(e->s)->bad_frames >= 5);
    env_free(e);
}

static void test_hello_mid_scan_abandons_it(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    uint8_t m[1000] = {0};
    scan_started(e);
    model_frame(e, m, sizeof m, 0, 0);
    pump(e);
    size_t from = mem_transport_sent_count(e->t);
    assert_int_equal(scan_session_hello(e->s, e->clock), 0);
    pump(e);
    assert_int_equal(e->dropped, 1);
    assert_false(scan_session_ready(e->s));
    const mem_frame *h = mem_transport_sent(e->t, from);
    assert_int_equal(h->type, PROTO_FSP_HELLO);
    assert_int_equal(h->seq, 0);
    env_free(e);
}

static void test_duplicate_model_frame_is_acked_again_not_counted(
    void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    uint8_t m[30000];
    for (size_t i = 0; i < sizeof m; i++)
        m[i] = (uint8_t)i;
    scan_started(e);
    size_t from = mem_transport_sent_count(e->t);
    uint16_t a = model_frame(e, m, sizeof m, 0, 0);
    pump(e);
    /* the ACK was lost: the device re-sends after its 5 s */
    uint16_t save = e->dseq;
    e->dseq = a;
    model_frame(e, m, sizeof m, 0, 0);
    e->dseq = save;
    model_frame(e, m, sizeof m, PROTO_FSP_MODEL_CHUNK_MAX, 0);
    scan_done(e, m, sizeof m, 0);
    pump(e);
    size_t acks = 0;
    for (size_t i = from; i < mem_transport_sent_count(e->t); i++) {
        const mem_frame *f = mem_transport_sent(e->t, i);
        acks += f->type == PROTO_FSP_ACK &&
                (f->payload[0] | f->payload[1] << 8) == a;
    }
    assert_int_equal(acks, 2);
    assert_int_equal(e->completed, 1);
    assert_memory_equal(e->model, m, sizeof m);
    env_free(e);
}

static void test_out_of_order_chunks_assemble(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    size_t total;
    uint8_t *m = load_model(&total);
    scan_started(e);
    /* the chunks travel in reverse order of offset */
    size_t nchunks = (total + PROTO_FSP_MODEL_CHUNK_MAX - 1) /
                     PROTO_FSP_MODEL_CHUNK_MAX;
    for (size_t k = nchunks; k > 0; k--)
        model_frame(e, m, total, (k - 1) * PROTO_FSP_MODEL_CHUNK_MAX, 0);
    scan_done(e, m, total, 0);
    pump(e);
    assert_int_equal(e->completed, 1);
    assert_memory_equal(e->model, m, total);
    free(m);
    env_free(e);
}

static void test_result_resent_until_acked_and_device_nak_resends(
    void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    proto_fsp_result r = {"j1", "succeeded", "/v1/jobs/j1", 10, 5, 0, true};
    size_t from = mem_transport_sent_count(e->t);
    assert_int_equal(scan_session_send_result(e->s, &r, e->clock), 0);
    pump(e);
    const mem_frame *f = mem_transport_last(e->t, PROTO_FSP_RESULT);
    assert_non_null(f);
    uint16_t rseq = f->seq;
    assert_non_null(strstr((const char *)f->payload, "\"job\":\"j1\""));
    wait_ms(e, 5000);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_RESULT, from), 2);
    assert_int_equal(mem_transport_last(e->t, PROTO_FSP_RESULT)->seq, rseq);
    /* the device NAKs it: sent again at once */
    uint8_t p[2];
    dev(e, PROTO_FSP_NAK, p, proto_fsp_build_seq(p, rseq), 0);
    pump(e);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_RESULT, from), 3);
    /* ACKed: no more re-sends */
    dev(e, PROTO_FSP_ACK, p, proto_fsp_build_seq(p, rseq), 0);
    pump(e);
    wait_ms(e, 20000);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_RESULT, from), 3);
    env_free(e);
}

/* Sends a whole scan of m (total bytes) and pumps; returns SCAN_DONE's
 * sequence number. */
static uint16_t whole_scan(env *e, const uint8_t *m, size_t total)
{
    scan_started(e);
    for (size_t off = 0; off < total; off += PROTO_FSP_MODEL_CHUNK_MAX)
        model_frame(e, m, total, off, 0);
    uint16_t done = scan_done(e, m, total, 0);
    pump(e);
    return done;
}

static void test_deferred_scan_done_is_acked_only_once_kept(void **state)
{
    (void)state;
    scan_session_cfg cfg;
    scan_session_cfg_default(&cfg);
    cfg.defer_done_ack = true;
    env *e = env_new_cfg(0, &cfg);
    greet(e);
    size_t total;
    uint8_t *m = load_model(&total);
    size_t from = mem_transport_sent_count(e->t);
    uint16_t done = whole_scan(e, m, total);
    assert_int_equal(e->completed, 1);
    assert_memory_equal(e->model, m, total);
    assert_false(acked(e, done, from));
    assert_int_equal(scan_session_get_stats(e->s)->scans_completed, 0);
    /* the device's timer re-sends SCAN_DONE meanwhile: not ACKed yet */
    uint16_t save = e->dseq;
    e->dseq = done;
    scan_done(e, m, total, 0);
    e->dseq = save;
    pump(e);
    assert_false(acked(e, done, from));
    assert_int_equal(e->completed, 1);
    assert_int_equal(scan_session_ack_done(e->s, true, e->clock), 0);
    pump(e);
    assert_true(acked(e, done, from));
    assert_int_equal(scan_session_ack_done(e->s, true, e->clock), -ENOENT);
    const scan_session_stats *st = scan_session_get_stats(e->s);
    assert_int_equal(st->scans_completed, 1);
    assert_int_equal(st->model_bytes, total);
    /* a scan the caller could not keep: ABORT instead of the ACK */
    from = mem_transport_sent_count(e->t);
    done = whole_scan(e, m, total);
    assert_int_equal(e->completed, 2);
    assert_int_equal(scan_session_ack_done(e->s, false, e->clock), 0);
    pump(e);
    assert_false(acked(e, done, from));
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_ABORT, from), 1);
    assert_int_equal(st->scans_completed, 1);
    assert_int_equal(st->scans_dropped, 1);
    /* a HELLO forgets an unanswered SCAN_DONE */
    whole_scan(e, m, total);
    assert_int_equal(scan_session_hello(e->s, e->clock), 0);
    assert_int_equal(scan_session_ack_done(e->s, true, e->clock), -ENOENT);
    free(m);
    env_free(e);
}

static void test_start_scan_rules(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    assert_int_equal(scan_session_start_scan(e->s, 3, e->clock), -EINVAL);
    assert_int_equal(scan_session_start_scan(e->s, 2, e->clock), 0);
    pump(e);
    const mem_frame *f = mem_transport_last(e->t, PROTO_FSP_START_SCAN);
    assert_non_null(f);
    assert_int_equal(f->payload[0], 2);
    scan_started(e);
    pump(e);
    assert_int_equal(scan_session_start_scan(e->s, 0, e->clock), -EBUSY);
    assert_int_equal(scan_session_abort(e->s, e->clock), 0);
    pump(e);
    assert_int_equal(e->dropped, 1);
    assert_non_null(mem_transport_last(e->t, PROTO_FSP_ABORT));
    env_free(e);
}

static void test_model_over_limit_is_dropped(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    scan_started(e);
    uint8_t p[8 + 4], b[4] = {0};
    size_t pl = proto_fsp_build_model(p, 0x7fffffffu, 0, b, 4);
    dev(e, PROTO_FSP_MODEL, p, pl, 0);
    pump(e);
    assert_int_equal(e->dropped, 1);
    assert_non_null(strstr(e->why, "limit"));
    assert_non_null(mem_transport_last(e->t, PROTO_FSP_ABORT));
    env_free(e);
}

static void test_sequence_jump_restarts_with_hello(void **state)
{
    (void)state;
    env *e = env_new(0);
    greet(e);
    size_t from = mem_transport_sent_count(e->t);
    e->dseq = 5000;
    scan_started(e);
    pump(e);
    assert_int_equal(mem_transport_count(e->t, PROTO_FSP_HELLO, from), 1);
    assert_false(scan_session_ready(e->s));
    assert_int_equal(scan_session_get_stats(e->s)->restarts, 1);
    env_free(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(
            test_frames_before_info_are_ignored_and_get_info_repeats),
        cmocka_unit_test(test_whole_scan_in_small_reads),
        cmocka_unit_test(test_corrupted_model_frame_is_naked_and_resent),
        cmocka_unit_test(test_missing_frame_holds_scan_done_until_resent),
        cmocka_unit_test(
            test_wrong_model_crc_is_naked_three_times_then_dropped),
        cmocka_unit_test(test_scan_given_up_after_30s_without_a_frame),
        cmocka_unit_test(test_chunk_outside_total_is_naked_then_scan_dropped),
        cmocka_unit_test(test_hello_mid_scan_abandons_it),
        cmocka_unit_test(
            test_duplicate_model_frame_is_acked_again_not_counted),
        cmocka_unit_test(test_out_of_order_chunks_assemble),
        cmocka_unit_test(
            test_result_resent_until_acked_and_device_nak_resends),
        cmocka_unit_test(test_deferred_scan_done_is_acked_only_once_kept),
        cmocka_unit_test(test_start_scan_rules),
        cmocka_unit_test(test_model_over_limit_is_dropped),
        cmocka_unit_test(test_sequence_jump_restarts_with_hello),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
