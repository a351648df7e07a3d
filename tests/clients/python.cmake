# The Python package (clients/python) with Debian's python3 and python3-numpy: its codecs against
# the golden fixtures and the real meshoptimizer library, its numpy evaluation of the parameters
# against the spec's in float64, its ctypes paths through libmeshoptimizer and the C++ client
# library against the numpy ones, pip install without the network, and
# end to end against the real skinstreamd on the demo subject (tests/clients/python/), and across a
# subject swapped at run time.
find_program(SKINSTREAM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT SKINSTREAM_PYTHON)
  message(STATUS "Python package tests: /usr/bin/python3 not found (scripts/install-deps.sh); python.* not added")
elseif(TARGET skinstreamd)
  set(python_test_environment
    SKINSTREAMD=$<TARGET_FILE:skinstreamd>
    SKINSTREAM_CLI=$<TARGET_FILE:skinstream>
    SKINSTREAM_DEMO_DIR=${CMAKE_BINARY_DIR}/demo
    SKINSTREAM_TEST_TMP_DIR=${CMAKE_BINARY_DIR}/test_tmp/python
    SKINSTREAM_SWAP_SUBJECTS_DIR=${CMAKE_BINARY_DIR}/test_tmp/swap_subjects
    ${uninstrumented_host_environment})
  set(python_tests vertex_codec meshoptimizer_library protocol evaluation normals decoder_choice install subscriber receiver subject_swap)
  if(TARGET skinstream_client)  # the package's fast path for the parameters, through its C ABI
    list(APPEND python_test_environment SKINSTREAM_CLIENT_LIBRARY=$<TARGET_FILE:skinstream_client>)
    list(APPEND python_tests client_library)
  endif()
  foreach(name ${python_tests})
    add_test(NAME python.${name} COMMAND ${SKINSTREAM_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/python/${name}_test.py)
    set_tests_properties(python.${name} PROPERTIES ENVIRONMENT "${python_test_environment}" LABELS clients TIMEOUT ${time_limit_300})
  endforeach()
  set_tests_properties(python.subscriber python.receiver PROPERTIES FIXTURES_REQUIRED demo_subject)
  # A subject swapped at run time (POST /subjects/NAME/file) under the Subscriber and Receiver.
  set_tests_properties(python.subject_swap PROPERTIES FIXTURES_REQUIRED swap_subjects)
endif()
