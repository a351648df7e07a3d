# The C++ client library (clients/cpp) against the real skinstreamd on loopback, and against
# bytes that break the protocol; its evaluator's C ABI likewise.
if(TARGET skinstreamd AND TARGET skinstream_client)
  add_executable(client_library_tests ${CMAKE_CURRENT_LIST_DIR}/cpp/subscriber_test.cpp ${CMAKE_CURRENT_LIST_DIR}/cpp/evaluator_c_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/cpp/multicast_test.cpp ${PROJECT_SOURCE_DIR}/tests/support/test_data.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/daemon_process.cpp ${PROJECT_SOURCE_DIR}/tests/support/bridged_namespaces.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/program_run.cpp)
  target_include_directories(client_library_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  # skinstream_server for the daemon process harness the bench shares (server/client/daemon_process.h).
  target_link_libraries(client_library_tests PRIVATE skinstream_client skinstream_server nlohmann_json::nlohmann_json GTest::gtest_main)
  target_compile_definitions(client_library_tests PRIVATE
    SKINSTREAMD="$<TARGET_FILE:skinstreamd>"
    SKINSTREAM_DEMO_DIR="${CMAKE_BINARY_DIR}/demo"
    SKINSTREAM_SWAP_SUBJECTS_DIR="${CMAKE_BINARY_DIR}/test_tmp/swap_subjects"
    SKINSTREAM_SHARED_DIR="${SKINSTREAM_SHARED_DIR}"
    SKINSTREAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SKINSTREAM_TEST_TMP_DIR="${CMAKE_BINARY_DIR}/test_tmp/client_library")
  add_dependencies(client_library_tests skinstreamd)
  gtest_discover_tests(client_library_tests TEST_FILTER "-ClientSubscriberDemo.*:EvaluatorCDemo.*:MulticastDemo.*:MulticastKeyDemo.*:MulticastSwap.*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_120})
  # MulticastDemo needs root and iproute2 (network namespaces on a bridge); without them it is
  # skipped with the reason.
  gtest_discover_tests(client_library_tests TEST_FILTER "ClientSubscriberDemo.*:EvaluatorCDemo.*:MulticastDemo.*:MulticastKeyDemo.*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_300} FIXTURES_REQUIRED demo_subject COST 4)
  # Two subject files of one body (tests/support/make_swap_subjects.sh), swapped under a multicast receiver.
  gtest_discover_tests(client_library_tests TEST_FILTER "MulticastSwap.*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_300} FIXTURES_REQUIRED swap_subjects COST 6)
endif()
