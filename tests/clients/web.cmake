# The browser live preview (clients/web): build the bundle once (fixture web_bundle, which also
# installs the npm packages pinned in clients/web/package-lock.json), then
# - web.units: the page's decoders and tables in node (node's test runner);
# - web.bad_input: the page in the system Chromium against a scripted server sending bad input;
# - web.viewer: the page in Chromium against the real daemon (tests/clients/web/viewer_test.mjs);
# - web.takes_panel: the page's take controls against the real daemon (takes_panel_test.mjs);
# - web.calibration_panel: the page's live calibration against the real daemon;
# - web.subject_swap: the page drawing on across subjects swapped at run time (subject_swap_test.mjs).
# Needs node and npm (Debian: nodejs npm) and chromium (software WebGL).
find_program(SKINSTREAM_NODE NAMES node nodejs)
if(NOT TARGET skinstreamd)
  message(STATUS "browser test: skinstreamd is not built yet; the web tests are not added")
elseif(NOT SKINSTREAM_NODE)
  message(STATUS "browser test: node not found (apt-get install nodejs npm); the web tests are not added")
else()
  add_test(NAME web.bundle COMMAND ${PROJECT_SOURCE_DIR}/clients/web/build.sh ${CMAKE_BINARY_DIR}/web)
  set_tests_properties(web.bundle PROPERTIES FIXTURES_SETUP web_bundle LABELS browser TIMEOUT ${time_limit_600})

  set(web_tests ${CMAKE_CURRENT_SOURCE_DIR}/web)
  add_test(NAME web.units COMMAND ${SKINSTREAM_NODE} --test ${web_tests}/protocol_test.mjs ${web_tests}/model_message_test.mjs
    ${web_tests}/packed_message_test.mjs
    ${web_tests}/compressed_decoder_test.mjs ${web_tests}/evaluation_tables_test.mjs)
  set_tests_properties(web.units PROPERTIES FIXTURES_REQUIRED web_bundle TIMEOUT ${time_limit_300})

  add_test(NAME web.bad_input COMMAND ${SKINSTREAM_NODE} ${web_tests}/viewer_bad_input_test.mjs --web-root ${CMAKE_BINARY_DIR}/web)
  set_tests_properties(web.bad_input PROPERTIES FIXTURES_REQUIRED web_bundle LABELS browser TIMEOUT ${time_limit_600} PROCESSORS 2)

  add_test(NAME web.viewer COMMAND ${SKINSTREAM_NODE} ${web_tests}/viewer_test.mjs
    --daemon $<TARGET_FILE:skinstreamd>
    --cli $<TARGET_FILE:skinstream>
    --subject ${CMAKE_BINARY_DIR}/demo/subject.sksubj
    --recording ${CMAKE_BINARY_DIR}/demo/live.c3d
    --web-root ${CMAKE_BINARY_DIR}/web
    --out ${CMAKE_BINARY_DIR}/test_tmp/web)
  # The page's take controls against the real daemon with a record_dir and a control token.
  add_test(NAME web.takes_panel COMMAND ${SKINSTREAM_NODE} ${web_tests}/takes_panel_test.mjs
    --daemon $<TARGET_FILE:skinstreamd>
    --subject ${CMAKE_BINARY_DIR}/demo/subject.sksubj
    --recording ${CMAKE_BINARY_DIR}/demo/live.c3d
    --web-root ${CMAKE_BINARY_DIR}/web
    --out ${CMAKE_BINARY_DIR}/test_tmp/web)
  set_tests_properties(web.takes_panel PROPERTIES FIXTURES_REQUIRED "web_bundle;demo_subject"
    LABELS browser TIMEOUT ${time_limit_300})
  # The page's live calibration: a CMU capture's subject recorded, built, checked and swapped in.
  add_test(NAME web.calibration_panel COMMAND ${SKINSTREAM_NODE} ${web_tests}/calibration_panel_test.mjs
    --daemon $<TARGET_FILE:skinstreamd>
    --subject ${CMAKE_BINARY_DIR}/test_tmp/swap_subjects/first.sksubj
    --capture ${PROJECT_SOURCE_DIR}/replay_data/cmu/85_02.c3d
    --mesh ${PROJECT_SOURCE_DIR}/replay_data/makehuman/makehuman_hm08_body_only.obj
    --web-root ${CMAKE_BINARY_DIR}/web
    --out ${CMAKE_BINARY_DIR}/test_tmp/web)
  # Two processors: the builder runs at the lowest priority, and beside Chromium it waited minutes.
  set_tests_properties(web.calibration_panel PROPERTIES FIXTURES_REQUIRED "web_bundle;swap_subjects" LABELS browser TIMEOUT ${time_limit_300} PROCESSORS 2)
  # Two pages (parameters on the GPU, compressed) across a subject file swapped in and back.
  add_test(NAME web.subject_swap COMMAND ${SKINSTREAM_NODE} ${web_tests}/subject_swap_test.mjs
    --daemon $<TARGET_FILE:skinstreamd>
    --first ${CMAKE_BINARY_DIR}/test_tmp/swap_subjects/first.sksubj
    --second ${CMAKE_BINARY_DIR}/test_tmp/swap_subjects/second.sksubj
    --recording ${PROJECT_SOURCE_DIR}/replay_data/cmu/85_02.c3d
    --web-root ${CMAKE_BINARY_DIR}/web
    --out ${CMAKE_BINARY_DIR}/test_tmp/web)
  set_tests_properties(web.subject_swap PROPERTIES FIXTURES_REQUIRED "web_bundle;swap_subjects"
    LABELS browser TIMEOUT ${time_limit_300} PROCESSORS 2)
  # Chromium with SwiftShader keeps both cores busy: let ctest -j count it as two.
  set_tests_properties(web.viewer PROPERTIES FIXTURES_REQUIRED "web_bundle;demo_subject"
    LABELS browser TIMEOUT ${time_limit_600} PROCESSORS 2)
endif()
