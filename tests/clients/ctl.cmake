# skinstream-ctl, the real program: usage errors exit 2, a refusal or an unreachable daemon 1.
# Its exchanges with a control API are tested against a real HTTP server in
# tests/server/control/control_ctl_program_test.cpp.
add_test(NAME ctl.help COMMAND skinstream-ctl --help)
set_tests_properties(ctl.help PROPERTIES PASS_REGULAR_EXPRESSION "take.*takes")
# Each line: the arguments, then the exit code they must give.
add_test(NAME ctl.exit_codes COMMAND bash -c [=[
ctl=$0
expect() {
  local want=$1; shift
  SKINSTREAM_CONTROL_TOKEN=stage-token-0123456789 "$ctl" "$@" > /dev/null 2>&1
  local got=$?
  if [ "$got" -ne "$want" ]; then echo "skinstream-ctl $*: exit $got, expected $want"; exit 1; fi
}
expect 2
expect 2 take
expect 2 take begin
expect 2 takes extra
expect 2 --port 70000 takes
expect 2 --token-file /nonexistent/token takes
# No daemon on port 1: not a usage error, a failure.
expect 1 --port 1 takes
SKINSTREAM_CONTROL_TOKEN= "$ctl" takes > /dev/null 2>&1; got=$?
if [ "$got" -ne 2 ]; then echo "without a token: exit $got, expected 2"; exit 1; fi
echo ok
]=] $<TARGET_FILE:skinstream-ctl>)
set_tests_properties(ctl.help ctl.exit_codes PROPERTIES LABELS clients)
set_tests_properties(ctl.exit_codes PROPERTIES PASS_REGULAR_EXPRESSION "^ok")
