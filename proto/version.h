/* version.h — the one version number of facet and facetd (the CLI's
 * --version, /v1/version, the scanner hello). */
#ifndef FACET_VERSION_H
#define FACET_VERSION_H

#define FACET_VERSION "0.1.0"

#endif
