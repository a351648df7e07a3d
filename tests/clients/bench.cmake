# skinstream-bench, the real program, for a few seconds on loopback (its report checked for
# consistency, not for speed: figures are measured by running it, see the README), bad paths
# failing clearly; and its stall log and child commands alone.
if(TARGET skinstream-bench AND TARGET skinstreamd)
  add_executable(bench_tests ${CMAKE_CURRENT_LIST_DIR}/bench_e2e_test.cpp ${CMAKE_CURRENT_LIST_DIR}/bench/stall_log_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/bench/child_command_test.cpp ${PROJECT_SOURCE_DIR}/clients/bench/child_command.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/test_data.cpp ${PROJECT_SOURCE_DIR}/tests/support/program_run.cpp)
  target_include_directories(bench_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR})
  target_link_libraries(bench_tests PRIVATE nlohmann_json::nlohmann_json GTest::gtest_main)
  target_compile_definitions(bench_tests PRIVATE
    SKINSTREAM_BENCH="$<TARGET_FILE:skinstream-bench>"
    SKINSTREAM_DEMO_DIR="${CMAKE_BINARY_DIR}/demo"
    SKINSTREAM_SHARED_DIR="${SKINSTREAM_SHARED_DIR}"
    SKINSTREAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SKINSTREAM_TEST_TMP_DIR="${CMAKE_BINARY_DIR}/test_tmp/bench")
  add_dependencies(bench_tests skinstream-bench skinstreamd)
  gtest_discover_tests(bench_tests TEST_FILTER "StallLog.*:ChildCommand.*" DISCOVERY_TIMEOUT 60 PROPERTIES LABELS clients)
  gtest_discover_tests(bench_tests TEST_FILTER "BenchProgram.*-BenchProgram.ShapedLink*:BenchProgram.Interrupted*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_120} FIXTURES_REQUIRED demo_subject COST 4)
  # The shaped link's tests count the bench's network namespaces before and after: alone.
  gtest_discover_tests(bench_tests TEST_FILTER "BenchProgram.ShapedLink*:BenchProgram.Interrupted*" DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS clients TIMEOUT ${time_limit_120} FIXTURES_REQUIRED demo_subject RUN_SERIAL TRUE)
endif()
