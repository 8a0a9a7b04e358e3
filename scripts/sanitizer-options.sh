# Sourced by scripts/test-sanitizers.sh and scripts/fuzz.sh: stop at the
# first report, with its stack.
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
