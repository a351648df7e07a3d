# The Blender add-on (clients/blender) in Debian's Blender 3.4, headless: its zip (with the
# Python package inside) installed and enabled, then tests/clients/blender/addon_test.py against
# the real daemon on the demo subject, and across a subject swapped at run time (swap_subjects).
# BLENDER_USER_SCRIPTS keeps the install in the build tree.
find_program(SKINSTREAM_BLENDER blender)
find_program(SKINSTREAM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT SKINSTREAM_BLENDER OR NOT SKINSTREAM_PYTHON)
  message(STATUS "Blender add-on test: blender or /usr/bin/python3 not found (scripts/install-deps.sh); blender.* not added")
elseif(TARGET skinstreamd)
  set(addon_zip ${CMAKE_BINARY_DIR}/blender/skinstream_live.zip)
  add_test(NAME blender.addon_zip COMMAND ${SKINSTREAM_PYTHON} ${PROJECT_SOURCE_DIR}/clients/blender/make_addon_zip.py ${addon_zip})
  set_tests_properties(blender.addon_zip PROPERTIES FIXTURES_SETUP blender_addon LABELS clients)
  add_test(NAME blender.addon COMMAND ${SKINSTREAM_BLENDER} -b --factory-startup --python-exit-code 1
    --python ${CMAKE_CURRENT_LIST_DIR}/blender/addon_test.py -- ${addon_zip})
  set_tests_properties(blender.addon PROPERTIES
    ENVIRONMENT "BLENDER_USER_SCRIPTS=${CMAKE_BINARY_DIR}/test_tmp/blender/scripts;SKINSTREAMD=$<TARGET_FILE:skinstreamd>;SKINSTREAM_CLI=$<TARGET_FILE:skinstream>;SKINSTREAM_DEMO_DIR=${CMAKE_BINARY_DIR}/demo;SKINSTREAM_TEST_TMP_DIR=${CMAKE_BINARY_DIR}/test_tmp/blender;SKINSTREAM_SWAP_SUBJECTS_DIR=${CMAKE_BINARY_DIR}/test_tmp/swap_subjects"
    FIXTURES_REQUIRED "blender_addon;demo_subject;swap_subjects" LABELS clients TIMEOUT ${time_limit_600})
  if(TARGET skinstream_client)  # the fast path for the parameters the carried package finds
    set_property(TEST blender.addon APPEND PROPERTY ENVIRONMENT SKINSTREAM_CLIENT_LIBRARY=$<TARGET_FILE:skinstream_client>)
  endif()
  if(uninstrumented_host_environment)
    set_property(TEST blender.addon APPEND PROPERTY ENVIRONMENT ${uninstrumented_host_environment})
  endif()
endif()
