# A real QTM RT client, the npm package qualisys-rt (MIT), unmodified, reads
# `skinstream-replay --protocol qtm` streaming two recordings (a dense synthetic one with gaps and
# unlabelled points, and a CMU take) and checks labels, frame numbers and coordinates against the
# recordings' TRC conversions (tests/clients/qualisys_rt/qtm_client_test.js). Needs node and npm;
# the package is pinned in tests/clients/qualisys_rt/package-lock.json and installed by install.sh.
find_program(SKINSTREAM_NODE NAMES node nodejs)
set(qtm_tmp ${CMAKE_BINARY_DIR}/test_tmp/qtm)
file(MAKE_DIRECTORY ${qtm_tmp})
set(qtm_dense ${PROJECT_SOURCE_DIR}/replay_data/synthetic/flex_2s_seed1.c3d)
set(qtm_cmu ${PROJECT_SOURCE_DIR}/replay_data/cmu/85_02.c3d)

if(NOT SKINSTREAM_NODE)
  message(STATUS "QTM client test: node not found (apt-get install nodejs npm); qtm.qualisys_rt not added")
else()
  add_test(NAME qtm.install_qualisys_rt COMMAND ${PROJECT_SOURCE_DIR}/tests/clients/qualisys_rt/install.sh)
  set_tests_properties(qtm.install_qualisys_rt PROPERTIES FIXTURES_SETUP qualisys_rt LABELS clients TIMEOUT ${time_limit_600})
  add_test(NAME qtm.recordings_as_trc COMMAND bash -c [=["$0" convert "$1" "$3/dense.trc" && "$0" convert "$2" "$3/cmu.trc"]=]
    $<TARGET_FILE:skinstream> ${qtm_dense} ${qtm_cmu} ${qtm_tmp})
  set_tests_properties(qtm.recordings_as_trc PROPERTIES FIXTURES_SETUP qtm_recordings LABELS clients)
  add_test(NAME qtm.qualisys_rt_reads_replay COMMAND ${SKINSTREAM_NODE}
    ${PROJECT_SOURCE_DIR}/tests/clients/qualisys_rt/qtm_client_test.js $<TARGET_FILE:skinstream-replay>
    ${qtm_dense}:${qtm_tmp}/dense.trc ${qtm_cmu}:${qtm_tmp}/cmu.trc)
  set_tests_properties(qtm.qualisys_rt_reads_replay PROPERTIES FIXTURES_REQUIRED "qualisys_rt;qtm_recordings"
    LABELS clients TIMEOUT ${time_limit_120} PASS_REGULAR_EXPRESSION "qualisys-rt received 810 frames of 391 labels")
endif()

# skinstream-replay's QTM RT and NatNet modes: bad command lines fail with one error line.
set(other_rate ${SKINSTREAM_SHARED_DIR}/data/captures/kineticstoolkit/kinematics_tennis_serve.c3d)
add_test(NAME replay.vicon_rates_must_agree COMMAND skinstream-replay ${qtm_cmu} ${other_rate} --port 0)
set_tests_properties(replay.vicon_rates_must_agree PROPERTIES PASS_REGULAR_EXPRESSION "error: .* Hz; pass --rate")
add_test(NAME replay.unknown_protocol COMMAND skinstream-replay --protocol motive ${qtm_cmu} --port 0)
add_test(NAME replay.rates_must_agree COMMAND skinstream-replay --protocol natnet ${qtm_cmu} ${other_rate} --port 0)
set_tests_properties(replay.rates_must_agree PROPERTIES PASS_REGULAR_EXPRESSION "error: .* Hz; pass --rate")
add_test(NAME replay.bad_natnet_version COMMAND skinstream-replay --protocol natnet --natnet-version 2.9 ${qtm_cmu} --port 0)
add_test(NAME replay.qtm_missing_file COMMAND skinstream-replay --protocol qtm ${qtm_cmu} ${qtm_tmp}/no_such_take.c3d --port 0)
set_tests_properties(replay.qtm_missing_file PROPERTIES PASS_REGULAR_EXPRESSION "error: .*no_such_take.c3d: ")
# Played to the end without clients, exit 0.
add_test(NAME replay.qtm_plays_to_the_end COMMAND skinstream-replay --protocol qtm ${qtm_cmu} ${qtm_dense} --port 0 --start-now --speed 50)
add_test(NAME replay.natnet_plays_to_the_end COMMAND skinstream-replay --protocol natnet --unicast ${qtm_cmu} --port 0 --start-now --speed 50)
set_tests_properties(replay.unknown_protocol replay.bad_natnet_version PROPERTIES WILL_FAIL TRUE)
set_tests_properties(replay.vicon_rates_must_agree replay.unknown_protocol replay.rates_must_agree
  replay.bad_natnet_version replay.qtm_missing_file replay.qtm_plays_to_the_end replay.natnet_plays_to_the_end
  PROPERTIES LABELS clients)
