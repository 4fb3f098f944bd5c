/* test_http_listen.c — Listen= address forms parse, malformed ones are
 * refused with the address in the message, loopback is told apart from
 * public addresses (the API-token rule depends on it), and an opened
 * socket describes itself with its real port. */
#include "testutil.h"

#include <string.h>
#include <unistd.h>

#include "http_listen.h"

static void expect(const char *addr, int ok, bool loop)
{
    bool lo = !loop;
    geo_err err = {{0}};
    int r = http_listen_check(addr, &lo, &err);
    if (ok) {
        if (r != 0)
            fail_msg("%s: %s", addr, err.msg);
        if (lo != loop)
            fail_msg("%s: loopback %d, want %d", addr, lo, loop);
    } else {
        if (r == 0)
            fail_msg("%s parsed", addr);
        assert_non_null(strstr(err.msg, addr));
    }
}

static void test_address_forms_and_loopback(void **state)
{
    (void)state;
    expect("127.0.0.1:8080", 1, true);
    expect("127.1.2.3:80", 1, true);
    expect("localhost:8080", 1, true);
    expect("[::1]:8080", 1, true);
    expect("[::ffff:127.0.0.1]:8080", 1, true);
    expect("0.0.0.0:8080", 1, false);
    expect("192.168.1.5:8080", 1, false);
    expect(":8080", 1, false);
    expect("[::]:8080", 1, false);
    expect("127.0.0.1", 0, false);
    expect("127.0.0.1:65536", 0, false);
    expect("127.0.0.1:-1", 0, false);
    expect("example.com:80", 0, false);
    expect("[::1:80", 0, false);
    expect("127.0.0.1:", 0, false);
}

static void test_opened_socket_reports_its_port(void **state)
{
    (void)state;
    int fd;
    geo_err err = {{0}};
    assert_int_equal(http_listen_open("127.0.0.1:0", 8, &fd, &err), 0);
    char buf[64];
    bool lo = false;
    assert_int_equal(http_listen_describe(fd, buf, sizeof buf, &lo, &err), 0);
    assert_true(lo);
    assert_int_equal(strncmp(buf, "127.0.0.1:", 10), 0);
    assert_true(strcmp(buf, "127.0.0.1:0") != 0);
    close(fd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_address_forms_and_loopback),
        cmocka_unit_test(test_opened_socket_reports_its_port),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
