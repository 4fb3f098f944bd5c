/* http_openapi.c — the OpenAPI 3.1 document of the API (daemon/openapi.json,
 * checked in and tested against the route table), embedded in the binary
 * at build time with the assembler's .incbin so the served document is
 * always the one the binary was built with. */
#include <stddef.h>
#include <string.h>

#include "http.h"

__asm__(".section .rodata\n"
        ".balign 16\n"
        ".hidden facetd_openapi_start\n"
        "facetd_openapi_start:\n"
        ".incbin \"daemon/openapi.json\"\n"
        ".byte 0\n"
        ".previous\n");

extern const char facetd_openapi_start[];

const char *http_openapi_doc(size_t *ret_len)
{
    *ret_len = strlen(facetd_openapi_start);
    return facetd_openapi_start;
}
