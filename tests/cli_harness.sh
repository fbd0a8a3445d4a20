# Sourced by the end-to-end scripts of the dsreg command (cli_test.sh, cli_eval_test.sh): a
# scratch folder $work, pass/fail counters, `check`, `expect_error` and `finish`. The sourcing
# script sets OUTPUTS first: the glob, relative to $work, of the files a failed run must not leave.
set -u
: "${DSREG:?set DSREG to the dsreg executable}"
: "${OUTPUTS:?set OUTPUTS to the glob of the outputs a failed run must not leave, e.g. out.*}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
passes=0

check() {  # check NAME COMMAND... : the command must succeed
    local name=$1; shift
    if "$@"; then passes=$((passes + 1)); else echo "FAIL: $name"; failures=$((failures + 1)); fi
}

expect_error() {  # expect_error NAME TEXT ARGS... : dsreg ARGS exits 1, mentions TEXT, leaves no $work/$OUTPUTS
    local name=$1 text=$2; shift 2
    rm -rf "$work"/$OUTPUTS
    local err
    err=$("$DSREG" "$@" 2>&1 >/dev/null)
    local code=$?
    if [[ $code -ne 1 ]]; then echo "FAIL: $name: exit code $code (expected 1)"; failures=$((failures + 1)); return; fi
    if [[ $err != *"$text"* ]]; then echo "FAIL: $name: message '$err' lacks '$text'"; failures=$((failures + 1)); return; fi
    if compgen -G "$work/$OUTPUTS" >/dev/null || compgen -G "$work/.out*" >/dev/null; then
        echo "FAIL: $name: output file left behind"; failures=$((failures + 1)); return
    fi
    passes=$((passes + 1))
}

finish() {  # the summary line; the script's exit status
    echo "$passes passed, $failures failed"
    [[ $failures -eq 0 ]]
}
