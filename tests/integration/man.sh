#!/bin/bash
# man.sh — the man pages and the example configuration cannot drift:
# facet(1), facetd(8) and the generated facetd.conf(5) render with
# `man --warnings -l` and no warning; facetd.conf(5) and the checked-in
# systemd/facetd.conf.example describe every key `facetd --help` lists
# (the example is byte for byte what `facetd --dump-config-example`
# writes: `make config-example` rewrites it); facet(1) has a section for
# every command `facet --help` lists and names every option of each
# `facet COMMAND --help`. A command or key added without its
# documentation fails here.
. "$(dirname "$0")/lib.sh" "$@"

FACET="$BUILD/facet"
CONF5="$BUILD/man/facetd.conf.5"
PAGES=(man/facet.1 man/facetd.8 "$CONF5")

# The roff spelling of a name: every '-' as '\-'.
roff_name() { printf '%s' "$1" | sed 's/-/\\-/g'; }

check "the build wrote facetd.conf(5)" test -s "$CONF5"
"$FACETD" --dump-config-man >"$T/conf5"
check "facetd.conf(5) in the build is what facetd --dump-config-man writes" \
    cmp -s "$T/conf5" "$CONF5"

if command -v man >/dev/null && command -v groff >/dev/null; then
    warnings=0
    for page in "${PAGES[@]}"; do
        name=$(basename "$page")
        MANWIDTH=80 man --warnings -l "$page" >"$T/$name.txt" 2>"$T/$name.warn"
        n=$(grep -c . "$T/$name.warn")
        warnings=$((warnings + n))
        if [ "$n" -eq 0 ] && [ -s "$T/$name.txt" ]; then
            ok "$name renders with no warning"
        else
            not_ok "$name renders with no warning" "$(head -n 5 "$T/$name.warn")"
        fi
    done
    echo "# man warnings: $warnings"
else
    for page in "${PAGES[@]}"; do
        skip "$(basename "$page") renders (man or groff is not installed: make deps)"
    done
fi

# Every key of facetd --help: "  --flag=V  Key=  help (default: ...)".
"$FACETD" --help >"$T/help"
keys=$(sed -n 's/^  --[^ ]*  *\([A-Za-z]*\)=  .*/\1/p' "$T/help")
nkeys=$(echo "$keys" | grep -c .)
check "facetd --help lists keys" test "$nkeys" -ge 20
missing_man=""
missing_ex=""
for k in $keys; do
    grep -qF "\\fB$k=\\fR" "$CONF5" || missing_man="$missing_man $k"
    grep -q "^#$k=" systemd/facetd.conf.example || missing_ex="$missing_ex $k"
done
expect_eq "facetd.conf(5) describes all $nkeys keys of facetd --help" "" "$missing_man"
expect_eq "facetd.conf.example has all $nkeys keys of facetd --help" "" "$missing_ex"
echo "# keys checked: $nkeys"
"$FACETD" --dump-config-example >"$T/example"
if cmp -s "$T/example" systemd/facetd.conf.example; then
    ok "systemd/facetd.conf.example is what facetd --dump-config-example writes"
else
    not_ok "systemd/facetd.conf.example is what facetd --dump-config-example writes" \
        "run: make config-example" "$(diff "$T/example" systemd/facetd.conf.example | head -n 5)"
fi

# Every command of facet --help, and every option of its --help.
cmds=$("$FACET" --help | awk '/^commands:/ { f = 1; next } /^$/ { f = 0 }
                             f && /^  [a-z]/ { print $1 }')
ncmds=$(echo "$cmds" | grep -c .)
check "facet --help lists commands" test "$ncmds" -ge 10
missing_cmd=""
missing_opt=""
for c in $cmds; do
    grep -qxF ".SS $(roff_name "$c")" man/facet.1 || missing_cmd="$missing_cmd $c"
    for o in $("$FACET" "$c" --help 2>&1 | grep -o -- '--[a-z][a-z-]*' | sort -u); do
        [ "$o" = --help ] && continue
        grep -qF -- "$(roff_name "$o")" man/facet.1 || missing_opt="$missing_opt $c:$o"
    done
done
expect_eq "facet(1) has a section for each of the $ncmds commands of facet --help" \
    "" "$missing_cmd"
expect_eq "facet(1) names every option of every facet COMMAND --help" "" "$missing_opt"
echo "# commands checked: $ncmds"

# The unit points at the man pages.
check "facetd.service documents itself with man:facetd(8)" \
    grep -qx 'Documentation=man:facetd(8) man:facetd.conf(5)' systemd/facetd.service.in
finish
