# The C++ client library installed and used as a renderer author does (tests/clients/cpp/
# package_test.py): cmake --install into a scratch prefix, examples/ built out of tree with
# find_package(skinstream_client), run against the real daemon on the demo subject.
find_program(SKINSTREAM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(TARGET skinstream_client AND TARGET skinstreamd AND SKINSTREAM_PYTHON)
  add_test(NAME client_package.install_build_and_run_example
    COMMAND ${SKINSTREAM_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/cpp/package_test.py ${CMAKE_BINARY_DIR} ${PROJECT_SOURCE_DIR}
      $<TARGET_FILE:skinstreamd> ${CMAKE_BINARY_DIR}/demo ${CMAKE_BINARY_DIR}/test_tmp/client_package)
  set_tests_properties(client_package.install_build_and_run_example PROPERTIES
    FIXTURES_REQUIRED demo_subject LABELS clients TIMEOUT ${time_limit_600})
  if(uninstrumented_host_environment)
    set_property(TEST client_package.install_build_and_run_example APPEND PROPERTY ENVIRONMENT ${uninstrumented_host_environment})
  endif()
endif()
