# The browser live preview (clients/web) against the real daemon, in the system Chromium with
# software WebGL: build the bundle once (fixture web_bundle), then tests/clients/web/viewer_test.mjs.
# Needs node and npm (Debian: nodejs npm) and chromium; the npm packages are pinned in
# clients/web/package-lock.json and installed by clients/web/build.sh.
find_program(SKINSTREAM_NODE NAMES node nodejs)
if(NOT TARGET skinstreamd)
  message(STATUS "browser test: skinstreamd is not built yet; web.viewer not added")
elseif(NOT SKINSTREAM_NODE)
  message(STATUS "browser test: node not found (apt-get install nodejs npm); web.viewer not added")
else()
  add_test(NAME web.bundle COMMAND ${PROJECT_SOURCE_DIR}/clients/web/build.sh ${CMAKE_BINARY_DIR}/web)
  set_tests_properties(web.bundle PROPERTIES FIXTURES_SETUP web_bundle LABELS browser TIMEOUT 600)

  add_test(NAME web.viewer COMMAND ${SKINSTREAM_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/web/viewer_test.mjs
    --daemon $<TARGET_FILE:skinstreamd>
    --cli $<TARGET_FILE:skinstream>
    --subject ${CMAKE_BINARY_DIR}/demo/subject.sksubj
    --recording ${CMAKE_BINARY_DIR}/demo/live.c3d
    --web-root ${CMAKE_BINARY_DIR}/web
    --out ${CMAKE_BINARY_DIR}/test_tmp/web)
  # Chromium with SwiftShader keeps both cores busy: let ctest -j count it as two.
  set_tests_properties(web.viewer PROPERTIES FIXTURES_REQUIRED "web_bundle;demo_subject"
    LABELS browser TIMEOUT 600 PROCESSORS 2)
endif()
