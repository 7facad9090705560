#!/usr/bin/env bash
# Runs a pytest command under the sanitizers. LeakSanitizer checks for leaks
# when the interpreter exits, from a tracer thread that stops every other
# thread; that tracer itself crashes now and then ("Tracer caught signal 11",
# "LeakSanitizer has encountered a fatal error") with every test passed and
# no leak reported. Such a run, and only such a run, is run once more; a leak
# report, a test failure or a second crash fails.
out="$(mktemp)"
"$@" >"$out" 2>&1
rc=$?
cat "$out"
if [ "$rc" -ne 0 ] && grep -q "LeakSanitizer has encountered a fatal error" "$out" &&
   ! grep -q "detected memory leaks" "$out" && ! grep -qE "[0-9]+ failed" "$out"; then
  echo "== LeakSanitizer's own tracer crashed at exit (no leak was reported): running once more"
  "$@"
  rc=$?
fi
rm -f "$out"
exit "$rc"
