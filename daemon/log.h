/* log.h — facetd's log: one line per event on stderr, with a level and,
 * where there is one, the job id.
 *
 * Under systemd (JOURNAL_STREAM set) each line starts with the kernel-style
 * "<N>" priority prefix that journald turns into the entry's priority and
 * carries no timestamp (the journal adds its own); on a terminal or a file a
 * line reads "2024-05-01T12:00:00.123Z info job=ID message".
 *
 * Levels are syslog's (LOG_ERR … LOG_DEBUG from <syslog.h>). Every function
 * is thread-safe: a line is formatted into a local buffer and written with
 * one write(2), so lines of concurrent threads never interleave. Library
 * layers (lib/, proto/) never log; the daemon logs once, where it handles an
 * error. */
#ifndef FACETD_LOG_H
#define FACETD_LOG_H

#include <syslog.h>

/* Lines above this level (numerically greater) are dropped; default
 * LOG_INFO. Safe to call at any time from any thread. */
void log_set_level(int level);

/* The level named "err", "warning", "notice", "info" or "debug" (also
 * "error", "warn"); -1 for anything else. */
int log_level_from_name(const char *name);

/* Logs one line. job may be NULL (no job field). A message longer than
 * about 1 KiB is truncated; newlines in it are replaced by spaces so one
 * event stays one line. */
void log_msg(int level, const char *job, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
