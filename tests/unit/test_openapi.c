/* test_openapi.c — the embedded OpenAPI document is valid JSON, declares
 * OpenAPI 3.1, and lists exactly the server's routes (every route in the
 * route table is a path of the document and vice versa). The integration
 * test openapi.sh checks the other way round over HTTP: every documented
 * operation is served. */
#include "testutil.h"

#include <string.h>

#include <jansson.h>

#include "http.h"

static void test_document_is_openapi_3_1(void **state)
{
    (void)state;
    size_t len;
    const char *doc = http_openapi_doc(&len);
    assert_true(len > 1000);
    json_error_t je;
    json_t *root = json_loadb(doc, len, JSON_REJECT_DUPLICATES, &je);
    if (!root)
        fail_msg("openapi.json:%d:%d: %s", je.line, je.column, je.text);
    const char *v = json_string_value(json_object_get(root, "openapi"));
    assert_non_null(v);
    assert_int_equal(strncmp(v, "3.1", 3), 0);
    assert_non_null(json_object_get(json_object_get(root, "info"), "title"));
    json_decref(root);
}

static void test_paths_are_exactly_the_routes(void **state)
{
    (void)state;
    size_t len;
    const char *doc = http_openapi_doc(&len);
    json_t *root = json_loadb(doc, len, 0, NULL);
    json_t *paths = json_object_get(root, "paths");
    assert_non_null(paths);
    for (unsigned i = 0; i < http_nroutes; i++)
        if (!json_object_get(paths, http_route_names[i]))
            fail_msg("route %s is not documented", http_route_names[i]);
    assert_int_equal(json_object_size(paths), http_nroutes);
    json_decref(root);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_document_is_openapi_3_1),
        cmocka_unit_test(test_paths_are_exactly_the_routes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
