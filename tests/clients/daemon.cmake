# skinstreamd, skinstream-sub and skinstream-replay as a user runs them, on loopback sockets: a
# replayed take through the real daemon to the real subscriber, compared with the offline
# `skinstream fill`; a Vicon DataStream source (skinstream-replay) going away and coming back;
# the demo subject's vertex buffers against `skinstream fill` + `deform`; bad paths fail clearly.
if(TARGET skinstreamd AND TARGET skinstream-sub AND TARGET skinstream-replay)
  add_executable(daemon_tests ${CMAKE_CURRENT_LIST_DIR}/daemon_e2e_test.cpp ${CMAKE_CURRENT_LIST_DIR}/daemon_subjects_e2e_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/daemon_subscribers_e2e_test.cpp ${CMAKE_CURRENT_LIST_DIR}/daemon_takes_e2e_test.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/test_data.cpp ${PROJECT_SOURCE_DIR}/tests/support/program_run.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/loopback_peer.cpp ${PROJECT_SOURCE_DIR}/tests/support/daemon_process.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/subscriber_client.cpp)
  target_include_directories(daemon_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  # skinstream_server for the blocking subscriber client (tests/support/) the tests subscribe with.
  target_link_libraries(daemon_tests PRIVATE skinstream_server skinstream_protocol_offline nlohmann_json::nlohmann_json GTest::gtest_main)
  target_compile_definitions(daemon_tests PRIVATE
    SKINSTREAMD="$<TARGET_FILE:skinstreamd>"
    SKINSTREAM_SUB="$<TARGET_FILE:skinstream-sub>"
    SKINSTREAM_REPLAY="$<TARGET_FILE:skinstream-replay>"
    SKINSTREAM_CLI="$<TARGET_FILE:skinstream>"
    SKINSTREAM_CTL="$<TARGET_FILE:skinstream-ctl>"
    SKINSTREAM_DEMO_DIR="${CMAKE_BINARY_DIR}/demo"
    SKINSTREAM_SHARED_DIR="${SKINSTREAM_SHARED_DIR}"
    SKINSTREAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SKINSTREAM_TEST_TMP_DIR="${CMAKE_BINARY_DIR}/test_tmp/daemon")
  if(SKINSTREAM_SANITIZE MATCHES undefined)
    target_compile_definitions(daemon_tests PRIVATE SKINSTREAM_UBSAN_VPTR)  # its vptr check, on with undefined
  endif()
  add_dependencies(daemon_tests skinstreamd skinstream-sub skinstream-replay skinstream skinstream-ctl)
  gtest_discover_tests(daemon_tests TEST_FILTER "-DaemonDemo*" DISCOVERY_TIMEOUT 60 PROPERTIES LABELS clients TIMEOUT ${time_limit_120} COST 2)
  # The demo subject's tests need the demo_subject fixture (tests/clients/CMakeLists.txt).
  gtest_discover_tests(daemon_tests TEST_FILTER "DaemonDemo*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_300} FIXTURES_REQUIRED demo_subject COST 6)

  # Usage errors of the programs themselves.
  add_test(NAME daemon.unknown_flag COMMAND skinstreamd --no-such-flag)
  add_test(NAME daemon.without_subject COMMAND skinstreamd --http-port 0 --sub-port 0)
  add_test(NAME daemon.vicon_without_port COMMAND skinstreamd --vicon 127.0.0.1 --print-config)
  add_test(NAME sub.without_address COMMAND skinstream-sub)
  add_test(NAME sub.bad_address COMMAND skinstream-sub nohost)
  add_test(NAME daemon.deform_cpus_twice COMMAND skinstreamd --deform-cpus 1,1 --print-config)
  add_test(NAME daemon.bad_tcp_congestion_name COMMAND skinstreamd --subscriber-tcp-congestion "Not A Name" --print-config)
  set_tests_properties(daemon.unknown_flag daemon.without_subject daemon.vicon_without_port sub.without_address sub.bad_address
    daemon.deform_cpus_twice daemon.bad_tcp_congestion_name PROPERTIES WILL_FAIL TRUE LABELS clients)
  # --print-config says that a subscriber token is set, never what it is.
  file(WRITE ${CMAKE_BINARY_DIR}/test_tmp/daemon/token_config.json "{\"subscriber_token\": \"stage-secret-42\"}")
  add_test(NAME daemon.print_config_hides_token
    COMMAND skinstreamd --config ${CMAKE_BINARY_DIR}/test_tmp/daemon/token_config.json --print-config)
  set_tests_properties(daemon.print_config_hides_token PROPERTIES PASS_REGULAR_EXPRESSION "\"subscriber_token\": \"\\(set, 15 bytes, not shown\\)\""
    FAIL_REGULAR_EXPRESSION "stage-secret" LABELS clients)
  # A CPU the process may not use is refused at start with the reason (a daemon that started
  # anyway would run until the timeout and fail this).
  add_test(NAME daemon.deform_cpu_not_allowed COMMAND skinstreamd --subject ${CMAKE_BINARY_DIR}/demo/subject.sksubj
    --deform-cpus 0,4095 --http-port 0 --sub-port 0)
  set_tests_properties(daemon.deform_cpu_not_allowed PROPERTIES
    PASS_REGULAR_EXPRESSION "CPU 4095 is not one this process may run on" TIMEOUT ${time_limit_60} LABELS clients FIXTURES_REQUIRED demo_subject)
endif()
