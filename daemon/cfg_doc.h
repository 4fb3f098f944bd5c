/* cfg_doc.h — the documentation generated from the configuration table
 * (cfg.h): the man page facetd.conf(5) and the example file
 * systemd/facetd.conf.example, so that neither can drift from the keys
 * facetd accepts. facetd prints them with its hidden options
 * --dump-config-man and --dump-config-example; the build writes the man
 * page, and a test compares the checked-in example with the output. */
#ifndef FACETD_CFG_DOC_H
#define FACETD_CFG_DOC_H

#include <stdio.h>

/* Writes facetd.conf(5) as roff (man macros). */
void cfg_doc_man(FILE *out);

/* Writes the commented example configuration: every key with its
 * default, commented out, under its section. */
void cfg_doc_example(FILE *out);

#endif
