# skinstream-replay, the real program: it streams a recording as a Vicon DataStream server.
# Good paths check the output and a real TCP exchange; bad paths must fail with one error line.
set(replay_capture ${PROJECT_SOURCE_DIR}/replay_data/cmu/85_02.c3d)
set(replay_tmp ${CMAKE_BINARY_DIR}/test_tmp/replay)
file(MAKE_DIRECTORY ${replay_tmp})

add_test(NAME replay.help COMMAND skinstream-replay --help)
set_tests_properties(replay.help PROPERTIES PASS_REGULAR_EXPRESSION "first client asks for a frame")

# Plays the whole take at 50x without clients and exits 0, after printing the port as JSON.
add_test(NAME replay.plays_to_the_end COMMAND skinstream-replay ${replay_capture} --port 0 --start-now --speed 50)
add_test(NAME replay.prints_port_json COMMAND skinstream-replay ${replay_capture} --port 0 --start-now --speed 50)
set_tests_properties(replay.prints_port_json PROPERTIES PASS_REGULAR_EXPRESSION "{\"port\": [1-9][0-9]*}")

# Several recordings stream as several subjects of one stream; each needs its own name.
add_test(NAME replay.several_recordings COMMAND skinstream-replay ${replay_capture} ${PROJECT_SOURCE_DIR}/replay_data/cmu/85_12.c3d
  --subject Actor1 --subject Actor2 --port 0 --start-now --speed 50)
set_tests_properties(replay.several_recordings PROPERTIES PASS_REGULAR_EXPRESSION "as subject 'Actor1'.*as subject 'Actor2'")
add_test(NAME replay.subject_per_recording COMMAND skinstream-replay ${replay_capture} ${replay_capture} --subject Actor1 --port 0)
set_tests_properties(replay.subject_per_recording PROPERTIES PASS_REGULAR_EXPRESSION "error: --subject is given 1 times for 2 recordings")
add_test(NAME replay.one_name_twice COMMAND skinstream-replay ${replay_capture} ${replay_capture} --subject A --subject A --port 0)
set_tests_properties(replay.one_name_twice PROPERTIES PASS_REGULAR_EXPRESSION "error: two recordings stream as subject \"A\"")

# A real client over TCP (bash /dev/tcp): the server greets with ObjectEnums (type 100001 =
# a1 86 01 00, packet length 44), answers RequestFrame{true} with frames, then exits 0.
add_test(NAME replay.serves_a_tcp_client COMMAND bash -c [=[
out=$(mktemp)
"$0" "$1" --port 0 --speed 10 > "$out" 2>/dev/null &
pid=$!
for i in $(seq 200); do grep -q port "$out" && break; sleep 0.05; done
port=$(sed -E 's/[^0-9]//g' "$out")
exec 3<>/dev/tcp/127.0.0.1/$port
printf '\x01\x00\x2b\x1a\x09\x00\x00\x00\xa2\x86\x01\x00\x01\x00\x00\x00\x01' >&3
head -c 120 <&3 | od -An -tx1
wait $pid
echo "exit $?"
rm -f "$out"
]=] $<TARGET_FILE:skinstream-replay> ${replay_capture})
set_tests_properties(replay.serves_a_tcp_client PROPERTIES TIMEOUT ${time_limit_60}
  PASS_REGULAR_EXPRESSION "01 00 2b 1a 2c 00 00 00 a1 86 01 00[^!]*exit 0")

# Bad paths: a non-zero exit, and the error line naming the problem.
add_test(NAME replay.missing_file COMMAND skinstream-replay ${replay_tmp}/no_such_take.c3d --port 0)
add_test(NAME replay.missing_file_message COMMAND skinstream-replay ${replay_tmp}/no_such_take.c3d --port 0)
set_tests_properties(replay.missing_file_message PROPERTIES PASS_REGULAR_EXPRESSION "error: .*no_such_take.c3d: ")

add_test(NAME replay.truncated_file COMMAND bash -c [=[head -c 3000 "$1" > "$2" && exec "$0" "$2" --port 0 --start-now]=]
  $<TARGET_FILE:skinstream-replay> ${replay_capture} ${replay_tmp}/truncated.c3d)
add_test(NAME replay.truncated_file_message COMMAND bash -c [=[head -c 3000 "$1" > "$2" && exec "$0" "$2" --port 0 --start-now]=]
  $<TARGET_FILE:skinstream-replay> ${replay_capture} ${replay_tmp}/truncated_msg.c3d)
set_tests_properties(replay.truncated_file_message PROPERTIES PASS_REGULAR_EXPRESSION "error: .*truncated_msg.c3d: ")

add_test(NAME replay.port_out_of_range COMMAND skinstream-replay ${replay_capture} --port 70000)
add_test(NAME replay.port_not_a_number COMMAND skinstream-replay ${replay_capture} --port eighty)
add_test(NAME replay.port_message COMMAND skinstream-replay ${replay_capture} --port 70000)
set_tests_properties(replay.port_message PROPERTIES PASS_REGULAR_EXPRESSION "--port")
add_test(NAME replay.bad_speed COMMAND skinstream-replay ${replay_capture} --port 0 --speed 0)
add_test(NAME replay.loop_and_hold COMMAND skinstream-replay ${replay_capture} --port 0 --loop --hold)
add_test(NAME replay.bad_tcp_congestion COMMAND skinstream-replay ${replay_capture} --port 0 --tcp-congestion "Not A Name")
set_tests_properties(replay.bad_tcp_congestion PROPERTIES PASS_REGULAR_EXPRESSION "not a congestion control name")

set_tests_properties(replay.missing_file replay.truncated_file replay.port_out_of_range replay.port_not_a_number
  replay.bad_speed replay.loop_and_hold PROPERTIES WILL_FAIL TRUE)
set_tests_properties(replay.help replay.plays_to_the_end replay.prints_port_json replay.serves_a_tcp_client
  replay.missing_file replay.missing_file_message replay.truncated_file replay.truncated_file_message
  replay.port_out_of_range replay.port_not_a_number replay.port_message replay.bad_speed replay.loop_and_hold
  replay.bad_tcp_congestion replay.several_recordings replay.subject_per_recording replay.one_name_twice PROPERTIES LABELS clients)
