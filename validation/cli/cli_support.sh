# What the command-line tests share. Sourced after they set work (a
# scratch folder), failures and passed.

# expect STATUS DESCRIPTION -- COMMAND...: the exit status, one-line stderr on
# error, and no file left in "$work/out" when it fails.
expect() {
    local status=$1 what=$2
    shift 3
    rm -rf "$work/out" && mkdir -p "$work/out"
    "$@" >"$work/stdout" 2>"$work/stderr"
    local got=$?
    local problem=""
    [ "$got" -eq "$status" ] || problem="exit status $got, expected $status"
    if [ -z "$problem" ] && [ "$status" -ne 0 ]; then
        [ "$(wc -l <"$work/stderr")" -eq 1 ] || problem="stderr is not one line: $(cat "$work/stderr")"
        [ -z "$(ls -A "$work/out")" ] || problem="left files behind: $(ls -A "$work/out")"
    fi
    if [ -n "$problem" ]; then
        echo "FAIL: $what: $problem"
        sed 's/^/  | /' "$work/stderr"
        failures=$((failures + 1))
    else
        passed=$((passed + 1))
    fi
}
