# facetd — one entry point: make, make run, make test, make bench,
# make fuzz, make install (DESTDIR, PREFIX), make deps.
#
# Layout (docs/architecture.md): lib/GROUP/ → build/libfacet.a (geometry,
# libc/libm only), proto/ → build/libfacetproto.a (formats, pipelines, the
# op runner), scanner/ → build/libfacetscan.a, daemon/ → build/facetd,
# daemon/cli/ → build/facet. `make SANITIZE=1 …` builds the same under
# AddressSanitizer + UndefinedBehaviorSanitizer in build/asan.
#
# Layering is enforced by include paths: each lib group sees only the
# groups below it (LIB_DEPS_*), a group's private/ headers only itself, and
# lib/ sees nothing of proto/, scanner/ or daemon/. A file that includes
# upward does not build.

PREFIX  ?= /usr/local
DESTDIR ?=
CC      ?= cc
SANITIZE ?= 0

ifeq ($(SANITIZE),1)
B := build/asan
SANFLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all \
            -fno-omit-frame-pointer
OPT := -O1 -g
else
B := build
SANFLAGS :=
OPT := -O2 -g
endif

# Libraries come from pkg-config, evaluated lazily so that `make deps`
# works on a machine that does not have them yet.
PKG_PROTO   := jansson
PKG_SCANNER := libusb-1.0 hidapi-hidraw libudev
PKG_DAEMON  := libmicrohttpd sqlite3 libsystemd libpq
PKG_TEST    := cmocka
PKG_MOCK    := umockdev-1.0 glib-2.0 gobject-2.0
pkg_cflags = $(shell pkg-config --cflags $(1) 2>/dev/null)
pkg_libs   = $(shell pkg-config --libs $(1) 2>/dev/null)

override CFLAGS += -std=c11 -D_GNU_SOURCE -Wall -Wextra -Wpedantic -Werror \
    -Wshadow -Wno-unused-parameter -ffp-contract=off -MMD -MP \
    $(OPT) $(SANFLAGS)

# lib/ groups, lowest first, and the groups each may include.
LIB_GROUPS       := core inspect cut replanar mesh frep correct gem
LIB_DEPS_core    := core
LIB_DEPS_inspect := core inspect
LIB_DEPS_cut     := core inspect cut
LIB_DEPS_replanar:= core inspect replanar
LIB_DEPS_mesh    := core inspect cut mesh
LIB_DEPS_frep    := core inspect mesh frep
LIB_DEPS_correct := core inspect cut replanar correct correct/private
LIB_DEPS_gem     := core inspect gem
INC_LIB     := $(foreach g,$(LIB_GROUPS),-Ilib/$(g))
INC_PROTO   := $(INC_LIB) -Iproto
INC_SCANNER := $(INC_PROTO) -Iscanner
INC_DAEMON  := $(INC_SCANNER) -Idaemon
INC_CLI     := $(INC_PROTO) -Idaemon/cli
INC_TESTS   := $(INC_DAEMON) -Ilib/correct/private -Itests/support
override LDFLAGS += $(SANFLAGS)
LDLIBS_BASE := -lm -lpthread

LIB_SRCS     := $(sort $(foreach g,$(LIB_GROUPS),$(wildcard lib/$(g)/*.c)))
PROTO_SRCS   := $(sort $(wildcard proto/*.c))
SCANNER_SRCS := $(sort $(wildcard scanner/*.c))
DAEMON_MAINS := daemon/facetd.c
CLI_SRCS     := $(sort $(wildcard daemon/cli/*.c))
DAEMON_SRCS  := $(sort $(filter-out $(DAEMON_MAINS),$(wildcard daemon/*.c)))
UNIT_SRCS    := $(sort $(wildcard tests/unit/test_*.c))
BENCH_SRCS   := $(sort $(wildcard tests/bench/bench_*.c))
TOOL_SRCS    := $(sort $(wildcard tests/tools/*.c))
TESTLIB_SRCS := $(sort $(wildcard tests/support/*.c))

obj = $(patsubst %.c,$(B)/obj/%.o,$(1))

LIBFACET  := $(B)/libfacet.a
LIBPROTO  := $(B)/libfacetproto.a
LIBSCAN   := $(B)/libfacetscan.a
LIBDAEMON := $(B)/libfacetdaemon.a
FACETD    := $(B)/facetd
FACET     := $(B)/facet
UNIT_BINS := $(patsubst tests/unit/%.c,$(B)/tests/%,$(UNIT_SRCS))
BENCH_BINS:= $(patsubst tests/bench/%.c,$(B)/bench/%,$(BENCH_SRCS))
TOOL_BINS := $(patsubst tests/tools/%.c,$(B)/tools/%,$(TOOL_SRCS))

ALL_LIBS = $(LIBDAEMON) $(LIBSCAN) $(LIBPROTO) $(LIBFACET)
ALL_LDLIBS = $(call pkg_libs,$(PKG_DAEMON) $(PKG_SCANNER) $(PKG_PROTO)) $(LDLIBS_BASE)

.SECONDARY:
.PHONY: all deps test bench fuzz run install clean check-deps
all: $(LIBFACET) $(LIBPROTO) $(FACET) $(if $(wildcard daemon/facetd.c),$(FACETD))

define lib_group_rule
$$(B)/obj/lib/$(1)/%.o: lib/$(1)/%.c
	@mkdir -p $$(dir $$@)
	$$(CC) $$(CFLAGS) $$(foreach d,$$(LIB_DEPS_$(1)),-Ilib/$$(d)) -c $$< -o $$@
endef
$(foreach g,$(LIB_GROUPS),$(eval $(call lib_group_rule,$(g))))

$(B)/obj/proto/%.o: proto/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_PROTO) $(call pkg_cflags,$(PKG_PROTO)) -c $< -o $@
$(B)/obj/scanner/%.o: scanner/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_SCANNER) $(call pkg_cflags,$(PKG_PROTO) $(PKG_SCANNER)) -c $< -o $@
$(B)/obj/daemon/cli/%.o: daemon/cli/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_CLI) $(call pkg_cflags,$(PKG_PROTO)) -c $< -o $@
$(B)/obj/daemon/%.o: daemon/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_DAEMON) $(call pkg_cflags,$(PKG_PROTO) $(PKG_SCANNER) $(PKG_DAEMON)) -c $< -o $@

$(B)/obj/tests/%.o: tests/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_TESTS) $(call pkg_cflags,$(PKG_PROTO) $(PKG_DAEMON) $(PKG_TEST)) -c $< -o $@

$(LIBFACET): $(call obj,$(LIB_SRCS))
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^
$(LIBPROTO): $(call obj,$(PROTO_SRCS))
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^
$(LIBSCAN): $(call obj,$(SCANNER_SRCS))
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^
$(LIBDAEMON): $(call obj,$(DAEMON_SRCS))
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^

$(FACET): $(call obj,$(CLI_SRCS)) $(LIBPROTO) $(LIBFACET)
	$(CC) $(LDFLAGS) -o $@ $^ $(call pkg_libs,$(PKG_PROTO)) $(LDLIBS_BASE)
$(FACETD): $(call obj,daemon/facetd.c) $(ALL_LIBS)
	$(CC) $(LDFLAGS) -o $@ $^ $(ALL_LDLIBS)

# Man pages (man/): facet(1) and facetd(8) are written by hand;
# facetd.conf(5) is generated from the configuration table (daemon/cfg.c)
# by facetd itself, as is systemd/facetd.conf.example (make
# config-example rewrites it; tests/integration/man.sh fails when the
# checked-in copy differs).
MAN_GEN := $(B)/man/facetd.conf.5
$(MAN_GEN): $(FACETD)
	@mkdir -p $(dir $@)
	$(FACETD) --dump-config-man > $@.tmp && mv $@.tmp $@
all: $(if $(wildcard daemon/facetd.c),$(MAN_GEN))
.PHONY: config-example
config-example: $(FACETD)
	$(FACETD) --dump-config-example > systemd/facetd.conf.example

$(B)/tests/%: $(B)/obj/tests/unit/%.o $(call obj,$(TESTLIB_SRCS)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $^ $(call pkg_libs,$(PKG_TEST)) $(ALL_LDLIBS)
$(B)/bench/%: $(B)/obj/tests/bench/%.o $(call obj,$(TESTLIB_SRCS)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $^ $(ALL_LDLIBS)
$(B)/tools/%: $(B)/obj/tests/tools/%.o $(call obj,$(TESTLIB_SRCS)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $^ $(ALL_LDLIBS)

# Debian 12 packages the project builds, tests and runs with.
DEB_PKGS := build-essential pkg-config libjansson-dev libmicrohttpd-dev \
    libsqlite3-dev libsystemd-dev libusb-1.0-0-dev libhidapi-dev libudev-dev \
    libcmocka-dev umockdev libumockdev-dev libglib2.0-dev curl systemd \
    clang libclang-rt-14-dev wrk jq libpq-dev postgresql-15 man-db groff-base \
    chromium zlib1g-dev
deps:
	@sh tests/tools/install-deps.sh $(DEB_PKGS)

test: deps
	@$(MAKE) --no-print-directory all-tests SANITIZE=$(SANITIZE)
	@sh tests/run.sh $(B)

.PHONY: all-tests
all-tests: all $(UNIT_BINS) $(TOOL_BINS)

bench: all $(BENCH_BINS) $(TOOL_BINS)
	@sh tests/bench/run.sh $(B)

# Side-by-side benchmarks against CGAL (tests/bench/cgal_*.cpp): built only
# where libcgal-dev is installed (make bench-deps, which adds Eigen for
# CGAL's fairing); CGAL is never linked into facet or facetd.
CGAL_SRCS := $(sort $(wildcard tests/bench/cgal_*.cpp))
CGAL_BINS := $(if $(wildcard /usr/include/CGAL/version.h),\
    $(patsubst tests/bench/%.cpp,$(B)/bench/%,$(CGAL_SRCS)))
CXX ?= g++
$(B)/bench/cgal_%: tests/bench/cgal_%.cpp
	@mkdir -p $(dir $@)
	$(CXX) -std=c++17 -O2 -DNDEBUG -DCGAL_EIGEN3_ENABLED \
	    -I/usr/include/eigen3 -o $@ $< -lgmp -lmpfr $(LDLIBS_BASE)
bench: $(CGAL_BINS)
.PHONY: bench-deps
bench-deps: deps
	@sh tests/tools/install-deps.sh libcgal-dev libeigen3-dev g++

# fsp-mock, the mocked USB scanner harness of the tests (tests/mock/, the
# only code that links GLib and umockdev): a testbed playing FSP/1 devices.
MOCK_SRCS := $(sort $(wildcard tests/mock/*.c))
FSP_MOCK  := $(B)/fsp-mock
$(B)/obj/tests/mock/%.o: tests/mock/%.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(INC_SCANNER) $(call pkg_cflags,$(PKG_PROTO) $(PKG_MOCK)) -c $< -o $@
$(FSP_MOCK): $(call obj,$(MOCK_SRCS)) $(LIBPROTO) $(LIBFACET)
	$(CC) $(LDFLAGS) -o $@ $^ $(call pkg_libs,$(PKG_MOCK) $(PKG_PROTO)) \
	    $(LDLIBS_BASE)
all-tests: $(FSP_MOCK)
bench: $(FSP_MOCK)

# libFuzzer targets (tests/fuzz/fuzz_*.c), built with clang apart from the
# unit tests: make fuzz [FUZZ_SECONDS=60] runs each for FUZZ_SECONDS;
# FUZZ_RUNS=N runs each for N executions instead (FUZZ_SECONDS then bounds
# it), FUZZ_TARGETS="fuzz_a fuzz_b" picks some.
FUZZ_SECONDS ?= 60
FUZZ_RUNS    ?=
FUZZ_TARGETS ?=
FUZZ_CC      ?= clang
FUZZ_DIR     := build/fuzz
FUZZ_CFLAGS   = -std=c11 -D_GNU_SOURCE -g -O1 -fno-omit-frame-pointer \
    -fsanitize=fuzzer-no-link,address,undefined \
    -fno-sanitize-recover=undefined $(INC_PROTO) -Ilib/correct/private \
    $(call pkg_cflags,$(PKG_PROTO))
FUZZ_SRCS    := $(sort $(wildcard tests/fuzz/fuzz_*.c))
FUZZ_BINS    := $(patsubst tests/fuzz/%.c,$(FUZZ_DIR)/%,$(FUZZ_SRCS))
FUZZ_OBJS    := $(patsubst %.c,$(FUZZ_DIR)/obj/%.o,$(LIB_SRCS) $(PROTO_SRCS))
$(FUZZ_DIR)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -MMD -MP -c $< -o $@
$(FUZZ_DIR)/fuzz_%: tests/fuzz/fuzz_%.c $(FUZZ_OBJS)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -fsanitize=fuzzer -o $@ $^ \
	    $(call pkg_libs,$(PKG_PROTO)) -lm -lpthread
# The HTTP server target runs the whole daemon library in the fuzzer.
FUZZ_DAEMON_OBJS := $(patsubst %.c,$(FUZZ_DIR)/obj/%.o,$(SCANNER_SRCS) $(DAEMON_SRCS))
FUZZ_DAEMON_PKGS := $(PKG_PROTO) $(PKG_SCANNER) $(PKG_DAEMON)
$(FUZZ_DIR)/obj/scanner/%.o $(FUZZ_DIR)/obj/daemon/%.o: FUZZ_CFLAGS += \
    $(INC_DAEMON) $(call pkg_cflags,$(FUZZ_DAEMON_PKGS))
$(FUZZ_DIR)/fuzz_http_request: tests/fuzz/fuzz_http_request.c $(FUZZ_OBJS) \
    $(FUZZ_DAEMON_OBJS)
	$(FUZZ_CC) $(FUZZ_CFLAGS) $(INC_DAEMON) -fsanitize=fuzzer -o $@ $^ \
	    $(call pkg_libs,$(FUZZ_DAEMON_PKGS)) -lm -lpthread
# The same targets built with the ordinary compiler and a plain driver
# (tests/fuzz/replay.c): make test replays their seeds.
FUZZ_REPLAY_BINS := $(patsubst tests/fuzz/%.c,$(B)/fuzz-replay/%,$(FUZZ_SRCS))
$(B)/fuzz-replay/fuzz_%: $(B)/obj/tests/fuzz/fuzz_%.o \
    $(B)/obj/tests/fuzz/replay.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $^ $(ALL_LDLIBS)
all-tests: $(FUZZ_REPLAY_BINS)
fuzz: deps
	@$(MAKE) --no-print-directory $(FUZZ_BINS)
	@sh tests/fuzz/run.sh $(FUZZ_DIR) $(FUZZ_SECONDS) "$(FUZZ_RUNS)" $(FUZZ_TARGETS)

run: deps
	@$(MAKE) --no-print-directory all
	@mkdir -p var
	@if [ -x $(FACETD) ]; then \
	  echo "facetd on http://127.0.0.1:8080, store in ./var (Ctrl-C stops)"; \
	  echo "submit a sample model (in another terminal):"; \
	  echo "  (printf '{\"pipeline\":[\"inspect\"],\"model\":'; cat tests/data/models/brilliant.scan-k400.json; printf '}') |"; \
	  echo "    curl -s -H 'Content-Type: application/json' --data-binary @- http://127.0.0.1:8080/v1/jobs"; \
	  echo "  curl -s 'http://127.0.0.1:8080/v1/jobs/ID?wait=30'   # then /v1/jobs/ID/stats, /v1/jobs/ID/model?format=obj"; \
	  exec $(FACETD) --listen 127.0.0.1:8080 --state-dir ./var; \
	else $(FACET) --help; fi

install: all
	install -d $(DESTDIR)$(PREFIX)/bin
	install -m 0755 $(FACET) $(DESTDIR)$(PREFIX)/bin/facet
	if [ -x $(FACETD) ]; then install -m 0755 $(FACETD) $(DESTDIR)$(PREFIX)/bin/facetd; fi
	install -d $(DESTDIR)$(PREFIX)/lib/systemd/system $(DESTDIR)$(PREFIX)/lib/tmpfiles.d \
	    $(DESTDIR)$(PREFIX)/lib/sysusers.d $(DESTDIR)$(PREFIX)/share/doc/facetd
	sed -e 's|@bindir@|$(PREFIX)/bin|' \
	    systemd/facetd.service.in > $(DESTDIR)$(PREFIX)/lib/systemd/system/facetd.service
	install -m 0644 systemd/facetd.socket $(DESTDIR)$(PREFIX)/lib/systemd/system/facetd.socket
	install -m 0644 systemd/facetd.tmpfiles $(DESTDIR)$(PREFIX)/lib/tmpfiles.d/facetd.conf
	install -m 0644 systemd/facetd.sysusers $(DESTDIR)$(PREFIX)/lib/sysusers.d/facetd.conf
	install -m 0644 systemd/facetd.conf.example README.md $(DESTDIR)$(PREFIX)/share/doc/facetd/
	install -d $(DESTDIR)$(PREFIX)/share/doc/facetd/docs/kernels
	install -m 0644 docs/*.md $(DESTDIR)$(PREFIX)/share/doc/facetd/docs/
	install -m 0644 docs/kernels/*.md $(DESTDIR)$(PREFIX)/share/doc/facetd/docs/kernels/
	install -d $(DESTDIR)$(PREFIX)/share/man/man1 $(DESTDIR)$(PREFIX)/share/man/man5 \
	    $(DESTDIR)$(PREFIX)/share/man/man8
	install -m 0644 man/facet.1 $(DESTDIR)$(PREFIX)/share/man/man1/facet.1
	if [ -x $(FACETD) ]; then \
	  install -m 0644 man/facetd.8 $(DESTDIR)$(PREFIX)/share/man/man8/facetd.8 && \
	  install -m 0644 $(MAN_GEN) $(DESTDIR)$(PREFIX)/share/man/man5/facetd.conf.5; fi
	install -d $(DESTDIR)$(PREFIX)/lib/udev/rules.d
	install -m 0644 systemd/70-facetd-scanners.rules $(DESTDIR)$(PREFIX)/lib/udev/rules.d/

clean:
	rm -rf build

-include $(shell find build -name '*.d' 2>/dev/null)

# The OpenAPI document and the viewer's files are embedded with .incbin
# (no -MMD entry for them).
$(B)/obj/daemon/http_openapi.o: daemon/openapi.json
$(B)/obj/daemon/http_web.o: $(wildcard daemon/web/*)
# png_probe reads the browser test's screenshots (zlib's inflate).
$(B)/tools/png_probe: ALL_LDLIBS += -lz
