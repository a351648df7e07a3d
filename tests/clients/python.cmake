# The Python package (clients/python) with Debian's python3 and python3-numpy: its codecs against
# the golden fixtures and the real meshoptimizer library, pip install without the network, and
# end to end against the real skinstreamd on the demo subject (tests/clients/python/).
find_program(SKINSTREAM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT SKINSTREAM_PYTHON)
  message(STATUS "Python package tests: /usr/bin/python3 not found (scripts/install-deps.sh); python.* not added")
elseif(TARGET skinstreamd)
  set(python_test_environment
    SKINSTREAMD=$<TARGET_FILE:skinstreamd>
    SKINSTREAM_CLI=$<TARGET_FILE:skinstream>
    SKINSTREAM_DEMO_DIR=${CMAKE_BINARY_DIR}/demo
    SKINSTREAM_TEST_TMP_DIR=${CMAKE_BINARY_DIR}/test_tmp/python)
  foreach(name vertex_codec protocol install subscriber receiver)
    add_test(NAME python.${name} COMMAND ${SKINSTREAM_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/python/${name}_test.py)
    set_tests_properties(python.${name} PROPERTIES ENVIRONMENT "${python_test_environment}" LABELS clients TIMEOUT 300)
  endforeach()
  set_tests_properties(python.subscriber python.receiver PROPERTIES FIXTURES_REQUIRED demo_subject)
endif()
