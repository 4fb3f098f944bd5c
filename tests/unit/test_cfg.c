/* test_cfg.c — configuration precedence (defaults < file < drop-ins in
 * lexical order < flags), value forms (sizes, durations, booleans,
 * scanner lists, pipelines), errors that name the file and line, and the
 * reload classification. */
#include "testutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cfg.h"
#include "log.h"

static char dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/facet-cfg-XXXXXX");
    assert_non_null(mkdtemp(dir));
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
    return 0;
}

static const char *write_file(const char *name, const char *text)
{
    static char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

static void test_defaults_listen_on_loopback(void **state)
{
    (void)state;
    cfg c;
    cfg_defaults(&c);
    assert_string_equal(c.listen, "127.0.0.1:8080");
    assert_string_equal(c.api_token, "");
    assert_false(c.allow_unauthenticated);
    assert_int_equal(c.max_body, 64ull << 20);
    assert_int_equal(c.job_timeout_ms, 600000);
    assert_int_equal(c.retention_age_ms, 7ull * 86400 * 1000);
    assert_int_equal(c.log_level, LOG_INFO);
}

static void test_file_then_dropins_then_flags(void **state)
{
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "%s",
             write_file("facetd.conf",
                        "# comment\n[Server]\nListen = 0.0.0.0:9000\n"
                        "MaxBody=2M\n\n[Jobs]\nWorkers=3\nQueueSize=50\n"
                        "; another comment\n[Store]\nRetentionAge=2h\n"));
    char d[300];
    snprintf(d, sizeof d, "%s.d", path);
    assert_int_equal(mkdir(d, 0755), 0);
    write_file("facetd.conf.d/20-b.conf", "[Jobs]\nWorkers=5\n");
    write_file("facetd.conf.d/10-a.conf", "[Jobs]\nWorkers=4\nQueueSize=\n");
    write_file("facetd.conf.d/ignored.txt", "[Jobs]\nWorkers=99\n");
    char *argv[] = {"-c", path, "--max-body=1K", "--job-timeout", "90s",
                    "--allow-unauthenticated"};
    cfg c;
    geo_err err = {{0}};
    int r = cfg_load(&c, 6, argv, &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    assert_string_equal(c.listen, "0.0.0.0:9000");
    assert_int_equal(c.workers, 5);          /* 20-b.conf wins */
    assert_int_equal(c.queue_size, 1000);    /* empty value = default */
    assert_int_equal(c.max_body, 1024);      /* flag beats file */
    assert_int_equal(c.job_timeout_ms, 90000);
    assert_int_equal(c.retention_age_ms, 2 * 3600 * 1000);
    assert_true(c.allow_unauthenticated);
}

static void expect_error(const char *text, const char *needle)
{
    const char *path = write_file("bad.conf", text);
    char p[256];
    snprintf(p, sizeof p, "%s", path);
    char *argv[] = {"-c", p};
    cfg c;
    cfg_defaults(&c);
    c.workers = 77;
    geo_err err = {{0}};
    assert_int_equal(cfg_load(&c, 2, argv, &err), -EINVAL);
    if (!strstr(err.msg, needle))
        fail_msg("expected '%s' in '%s'", needle, err.msg);
    assert_int_equal(c.workers, 77); /* untouched on failure */
}

static void test_errors_name_file_line_and_key(void **state)
{
    (void)state;
    expect_error("[Jobs]\nWorkers=two\n", "bad.conf:2: Workers: expected a whole number");
    expect_error("[Jobs]\nWorkerz=2\n", "bad.conf:2: unknown key Workerz");
    expect_error("[Nope]\n", "bad.conf:1: unknown section [Nope]");
    expect_error("Workers=2\n", "bad.conf:1: Workers outside a [Section]");
    expect_error("[Server]\nMaxBody=12Q\n", "MaxBody: expected a size");
    expect_error("[Jobs]\nJobTimeout=5 parsecs\n", "JobTimeout: expected a duration");
    expect_error("[Jobs]\nWorkers=100000\n", "Workers: 100000 out of range");
    expect_error("[Server]\nAllowUnauthenticated=maybe\n", "expected yes or no");
    expect_error("[Log]\nLogLevel=loud\n", "LogLevel: expected err");
}

static void test_explicit_missing_file_fails_flags_checked(void **state)
{
    (void)state;
    cfg c;
    geo_err err = {{0}};
    char *a1[] = {"-c", "/nonexistent/facetd.conf"};
    assert_true(cfg_load(&c, 2, a1, &err) < 0);
    assert_non_null(strstr(err.msg, "/nonexistent/facetd.conf"));
    char *a2[] = {"-c", (char *)write_file("ok.conf", ""), "--no-such-flag=1"};
    assert_int_equal(cfg_load(&c, 3, a2, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "unknown option --no-such-flag"));
    char *a3[] = {"-c", (char *)write_file("ok.conf", ""), "--workers"};
    assert_int_equal(cfg_load(&c, 3, a3, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "--workers needs a value"));
    char *a4[] = {"-c", (char *)write_file("ok.conf", ""), "--queue-size=0"};
    assert_int_equal(cfg_load(&c, 3, a4, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "--queue-size: QueueSize: 0 out of range"));
}

static void test_token_file_is_read_and_trimmed(void **state)
{
    (void)state;
    char tok[256];
    snprintf(tok, sizeof tok, "%s", write_file("token", "  s3cret-token\n"));
    char conf[512];
    snprintf(conf, sizeof conf, "[Server]\nApiTokenFile=%s\n", tok);
    char path[256];
    snprintf(path, sizeof path, "%s", write_file("t.conf", conf));
    char *argv[] = {"-c", path};
    cfg c;
    geo_err err = {{0}};
    assert_int_equal(cfg_load(&c, 2, argv, &err), 0);
    assert_string_equal(c.api_token, "s3cret-token");
}

static void test_restart_only_keys_are_reported(void **state)
{
    (void)state;
    cfg a, b;
    cfg_defaults(&a);
    b = a;
    b.queue_size = 5;          /* reloadable */
    b.retention_bytes = 1 << 30;
    char buf[256];
    assert_int_equal(cfg_restart_only_changes(&a, &b, buf, sizeof buf), 0);
    snprintf(b.listen, sizeof b.listen, "127.0.0.1:9");
    b.workers = 9;
    assert_int_equal(cfg_restart_only_changes(&a, &b, buf, sizeof buf), 2);
    assert_non_null(strstr(buf, "Server.Listen"));
    assert_non_null(strstr(buf, "Jobs.Workers"));
}

static void test_scanner_lines_replace_the_default_list_then_add(
    void **state)
{
    (void)state;
    cfg c;
    cfg_defaults(&c);
    assert_true(c.scanners);
    assert_int_equal(c.nscanner, 2);
    assert_string_equal(c.scanner[0], "1d50:6150:bulk");
    assert_string_equal(c.scanner[1], "1d50:6151:hid");
    assert_false(c.scanner_set);
    assert_string_equal(c.scanner_pipeline, "correct");
    assert_false(c.scanner_pipeline_set);
    char path[256];
    snprintf(path, sizeof path, "%s",
             write_file("s.conf", "[Scanners]\nScanner=1d50:6150:bulk\n"
                                  "Scanner = 0483:5740:hid inspect\n"
                                  "Pipeline=inspect,triangulate\n"));
    char *argv[] = {"-c", path, "--scanner", "1234:abcd:bulk ./nope.json"};
    geo_err err = {{0}};
    /* a pipeline file that does not exist is an error naming it */
    assert_int_equal(cfg_load(&c, 4, argv, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "--scanner: Scanner: ./nope.json"));
    argv[3] = "1234:ABCD:bulk [\"inspect\"]";
    int r = cfg_load(&c, 4, argv, &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    assert_int_equal(c.nscanner, 3);
    assert_string_equal(c.scanner[1], "0483:5740:hid inspect");
    char dev[64];
    assert_string_equal(cfg_scanner_split(c.scanner[2], dev, sizeof dev),
                        "[\"inspect\"]");
    assert_string_equal(dev, "1234:ABCD:bulk");
    assert_true(c.scanner_pipeline_set);
    json_t *pj = cfg_pipeline_json(c.scanner_pipeline, &err);
    assert_non_null(pj);
    assert_int_equal(json_array_size(pj), 2);
    json_decref(pj);
    /* an empty line restores the default list; --no-scanners */
    snprintf(path, sizeof path, "%s",
             write_file("s.conf", "[Scanners]\nScanner=0483:5740:hid\n"
                                  "Scanner=\n"));
    char *argv2[] = {"-c", path, "--no-scanners"};
    assert_int_equal(cfg_load(&c, 3, argv2, &err), 0);
    assert_int_equal(c.nscanner, 2);
    assert_false(c.scanner_set);
    assert_false(c.scanners);
}

static void test_scanner_errors_name_the_line(void **state)
{
    (void)state;
    expect_error("[Scanners]\nScanner=1d50:615:usb\n",
                 "bad.conf:2: Scanner: \"1d50:615:usb\": transport must be");
    expect_error("[Scanners]\nScanner=1d50:6150:bulk\nScanner=1d50:6150:hid\n",
                 "bad.conf:3: Scanner: 1d50:6150 listed twice");
    expect_error("[Scanners]\nScanner=1d50:6150:bulk inspekt\n",
                 "bad.conf:2: Scanner: pipeline[0]");
    expect_error("[Scanners]\nPipeline=[\"inspect\"\n", "bad.conf:2: Pipeline:");
    expect_error("[Scanners]\nEnabled=perhaps\n", "expected yes or no");
}

static void test_scanner_list_needs_a_restart_pipeline_reloads(void **state)
{
    (void)state;
    cfg a, b;
    cfg_defaults(&a);
    b = a;
    snprintf(b.scanner_pipeline, sizeof b.scanner_pipeline, "inspect");
    char buf[256];
    assert_int_equal(cfg_restart_only_changes(&a, &b, buf, sizeof buf), 0);
    b.nscanner = 1;
    b.scanners = false;
    assert_int_equal(cfg_restart_only_changes(&a, &b, buf, sizeof buf), 2);
    assert_non_null(strstr(buf, "Scanners.Scanner"));
    assert_non_null(strstr(buf, "Scanners.Enabled"));
}

static void test_help_lists_every_flag(void **state)
{
    (void)state;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    cfg_print_help(f, "facetd");
    fclose(f);
    const char *flags[] = {"--listen", "--state-dir", "--workers",
                           "--queue-size", "--max-body", "--job-timeout",
                           "--retention-age", "--retention-bytes",
                           "--api-token", "--[no-]scanners", "--scanner=V",
                           "--scanner-pipeline"};
    for (size_t i = 0; i < sizeof flags / sizeof flags[0]; i++)
        assert_non_null(strstr(buf, flags[i]));
    free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
#define T(name) cmocka_unit_test_setup_teardown(name, setup, teardown)
        T(test_defaults_listen_on_loopback),
        T(test_file_then_dropins_then_flags),
        T(test_errors_name_file_line_and_key),
        T(test_explicit_missing_file_fails_flags_checked),
        T(test_token_file_is_read_and_trimmed),
        T(test_restart_only_keys_are_reported),
        T(test_scanner_lines_replace_the_default_list_then_add),
        T(test_scanner_errors_name_the_line),
        T(test_scanner_list_needs_a_restart_pipeline_reloads),
        T(test_help_lists_every_flag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
