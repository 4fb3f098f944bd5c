/* test_scan_config.c — the scanner device list: "VID:PID:bulk|hid"
 * entries, their errors (each naming the entry), duplicates, limits. */
#include "testutil.h"

#include <errno.h>
#include <string.h>

#include "config.h"

static void test_single_entries(void **state)
{
    (void)state;
    scan_match m;
    geo_err err;
    assert_int_equal(scan_match_parse("1d50:6150:bulk", &m, &err), 0);
    assert_int_equal(m.vid, 0x1d50);
    assert_int_equal(m.pid, 0x6150);
    assert_int_equal(m.kind, SCAN_KIND_BULK);
    assert_int_equal(scan_match_parse(" 1D50:6151:HID ", &m, &err), 0);
    assert_int_equal(m.kind, SCAN_KIND_HID);
    assert_int_equal(scan_match_parse("1:2:hid", &m, &err), 0);
    assert_int_equal(m.vid, 1);
    const char *bad[] = {"1d50:6150", "1d50:6150:usb", "1d50x:6150:bulk",
                         "12345:1:bulk", ":1:bulk", "1d50::hid", "",
                         "1d50:6150:bulk:x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        err.msg[0] = '\0';
        assert_int_equal(scan_match_parse(bad[i], &m, &err), -EINVAL);
        assert_true(strlen(err.msg) > 0);
    }
    scan_match_parse("1d50:6150:usb", &m, &err);
    assert_non_null(strstr(err.msg, "transport must be bulk or hid"));
}

static void test_lists(void **state)
{
    (void)state;
    scan_match m[SCAN_MATCH_MAX];
    size_t n = 0;
    geo_err err;
    assert_int_equal(scan_match_list_parse(SCAN_DEFAULT_DEVICES, m,
                                           SCAN_MATCH_MAX, &n, &err),
                     0);
    assert_int_equal(n, 2);
    assert_non_null(scan_match_find(m, n, 0x1d50, 0x6151, SCAN_KIND_HID));
    assert_null(scan_match_find(m, n, 0x1d50, 0x6151, SCAN_KIND_BULK));
    assert_int_equal(scan_match_list_parse("a:1:bulk b:2:hid,\tc:3:bulk", m,
                                           SCAN_MATCH_MAX, &n, &err),
                     0);
    assert_int_equal(n, 3);
    n = 77;
    assert_int_equal(scan_match_list_parse("a:1:bulk,a:1:hid", m,
                                           SCAN_MATCH_MAX, &n, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "devices[1]"));
    assert_int_equal(n, 77);
    assert_int_equal(scan_match_list_parse("a:1:bulk,zz:1:hid", m,
                                           SCAN_MATCH_MAX, &n, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "devices[1]: \"zz:1:hid\""));
    assert_int_equal(scan_match_list_parse(" , ", m, SCAN_MATCH_MAX, &n,
                                           &err),
                     -EINVAL);
    assert_int_equal(scan_match_list_parse("a:1:bulk,b:1:bulk", m, 1, &n,
                                           &err),
                     -EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_entries),
        cmocka_unit_test(test_lists),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
