# CLI tests of 'rowloc replay' (docs/localization-filter.md): runs on a simulated log, same bytes
# for the same log, readable by 'rowloc evaluate', and clear errors for bad input.
set(_replay_out ${CMAKE_CURRENT_BINARY_DIR}/replay)
set(_logs ${PROJECT_SOURCE_DIR}/tests/data/logs)
set(_swerve ${PROJECT_SOURCE_DIR}/config/vehicles/agrimaro-swerve.json)
file(MAKE_DIRECTORY ${_replay_out})
# On the tiles run of simulate_cli.cmake (fixture simulate_tiles): initialises from GNSS, all updates.
rowloc_cli_test(replay_runs_on_simulated_log ON "initialised at t=.*updates gnss: [0-9]+ accepted"
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve} -o ${_replay_out}/tiles-a.ndjson)
rowloc_cli_reproducible_test(replay_is_deterministic ${_replay_out}/tiles-b.ndjson ${_replay_out}/tiles-a.ndjson
                             replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                             --filter ${PROJECT_SOURCE_DIR}/config/filters/default.json -o ${_replay_out}/tiles-b.ndjson)
# With slip-aware odometry every estimate carries the wheels' calibration states (docs/protocol.md §3).
add_test(NAME apps.replay_writes_wheel_calibration
         COMMAND ${CMAKE_COMMAND} -DFILE=${_replay_out}/tiles-a.ndjson
                 "-DPATTERN=\"wheel_calibration\":{\"left_front\":{\"rolling_radius_m\":0\\.1[0-9]+,\"rolling_radius_sigma_m\":[0-9.e-]+,\"slip_compliance\":[0-9.e-]+,\"slip_compliance_sigma\":"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/file_contains.cmake)
set_tests_properties(apps.replay_writes_wheel_calibration PROPERTIES LABELS apps
                     FIXTURES_REQUIRED "simulate_tiles;replay_tiles")
# With wheel-angle states (config/filters/wheel-angles.json) the simulated log's encoder angles
# (angle_rad) make the odometry updates: the replay reports wheel_angles updates.
rowloc_cli_test(replay_uses_the_wheel_angles ON "updates wheel_angles: [1-9][0-9]+ accepted"
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/config/filters/wheel-angles.json -o ${_replay_out}/tiles-angles.ndjson)
set_tests_properties(apps.replay_uses_the_wheel_angles PROPERTIES FIXTURES_REQUIRED simulate_tiles)
# ... and evaluate compares R_w with the truth's rolling radius (tiles: 0.165 m).
rowloc_cli_test(replay_output_evaluates ON
                "position, total \\[m\\] +[0-9]+ +0\\.0[0-4].*Rolling radius per wheel.*left_front +[0-9]+ .* 0\\.16500"
                evaluate ${_sim_out}/tiles-a/truth.ndjson ${_replay_out}/tiles-a.ndjson --clip-to-truth
                -o ${_replay_out}/tiles-a-report --no-plots)
set_tests_properties(apps.replay_runs_on_simulated_log PROPERTIES FIXTURES_REQUIRED simulate_tiles
                     FIXTURES_SETUP replay_tiles)
set_tests_properties(apps.replay_is_deterministic apps.replay_output_evaluates
                     PROPERTIES FIXTURES_REQUIRED "simulate_tiles;replay_tiles")
# An out-of-range message is rejected by line number, counted, and the replay goes on.
rowloc_cli_test(replay_reports_rejected_input ON
                "out-of-range.ndjson:9: rejected: wheels at t=0.02 s: .speed_radps. above.*1 rejected inputs"
                replay ${_logs}/agrimaro-tiles-out-of-range.ndjson --vehicle ${_swerve} -o ${_replay_out}/range.ndjson)
rowloc_cli_test(replay_rejects_missing_log OFF "log .no-such-log.ndjson.: no such file"
                replay no-such-log.ndjson --vehicle ${_swerve} -o ${_replay_out}/missing.ndjson)
rowloc_cli_test(replay_rejects_missing_vehicle OFF "--vehicle .no-such-vehicle.json.: no such file"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle no-such-vehicle.json -o ${_replay_out}/x.ndjson)
rowloc_cli_test(replay_rejects_bad_filter OFF "bad-gate.json: gps.gate_probability must be in \\(0, 1\\)"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/tests/data/filters/bad-gate.json -o ${_replay_out}/x.ndjson)
rowloc_cli_test(replay_rejects_wrong_vehicle OFF "'left' is not a wheel of the vehicle 'agrimaro-swerve'|wheel order"
                replay ${_logs}/vineyard-002-1us-echoes.ndjson --vehicle ${_swerve} -o ${_replay_out}/x.ndjson)
# Without --map, ultrasonic pings are counted as read but unused; --skip drops a message type
# (ablation runs) and counts it.
rowloc_cli_test(replay_counts_unused_ultrasonic ON "22 ultrasonic pings read but not used"
                replay ${_logs}/vineyard-002-1us-echoes.ndjson
                --vehicle ${PROJECT_SOURCE_DIR}/config/vehicles/vineyard-ugv-4ws.json -o ${_replay_out}/pings.ndjson)
rowloc_cli_test(replay_skip_counts_skipped_messages ON "143 messages skipped \\(--skip imu\\)"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve} --skip imu -o ${_replay_out}/skip.ndjson)
rowloc_cli_test(replay_rejects_unknown_skip_type OFF "--skip"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve} --skip lidar -o ${_replay_out}/x.ndjson)
# With --map the echoes update the filter (map-aided update, issue 5): the one-sensor vineyard run of
# simulate_cli.cmake against its true row map; and clear errors for a missing or bad map and for a
# vehicle without rangers.
set(_ugv ${PROJECT_SOURCE_DIR}/config/vehicles/vineyard-ugv-4ws.json)
rowloc_cli_test(replay_map_aided_uses_echoes ON
                "map-aided \\(range\\): [0-9]+ echoes; [0-9]+ without a row segment.*map-aided association: [1-9][0-9]* echoes skipped with an uncertain heading, [0-9]+ with the sensor inside a canopy outline, [0-9]+ with an ambiguous lane.*updates ultrasonic: [0-9]+ accepted"
                replay ${_sim_out}/vineyard/sensors.ndjson --vehicle ${_ugv} --map ${_sim_out}/vineyard/row-map.geojson
                -o ${_replay_out}/vineyard-map.ndjson)
set_tests_properties(apps.simulate_runs_vineyard PROPERTIES FIXTURES_SETUP simulate_vineyard)
set_tests_properties(apps.replay_map_aided_uses_echoes PROPERTIES FIXTURES_REQUIRED simulate_vineyard)
rowloc_cli_test(replay_rejects_missing_map OFF "no-such-map.geojson"
                replay ${_logs}/vineyard-002-1us-echoes.ndjson --vehicle ${_ugv} --map no-such-map.geojson
                -o ${_replay_out}/x.ndjson)
rowloc_cli_test(replay_rejects_bad_map OFF "nan_coordinate.geojson"
                replay ${_logs}/vineyard-002-1us-echoes.ndjson --vehicle ${_ugv}
                --map ${PROJECT_SOURCE_DIR}/tests/data/maps/nan_coordinate.geojson -o ${_replay_out}/x.ndjson)
rowloc_cli_test(replay_rejects_map_without_rangers OFF "has no ultrasonic sensor to use it"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve}
                --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson -o ${_replay_out}/x.ndjson)
# --echo-log: one line per echo with the ellipse before and after it (tools/plot-echoes); it needs --map.
rowloc_cli_test(replay_writes_echo_log ON "wrote echo log .*vineyard-echoes\\.ndjson: [1-9][0-9]* echoes"
                replay ${_sim_out}/vineyard/sensors.ndjson --vehicle ${_ugv} --map ${_sim_out}/vineyard/row-map.geojson
                --echo-log ${_replay_out}/vineyard-echoes.ndjson -o ${_replay_out}/vineyard-map-2.ndjson)
set_tests_properties(apps.replay_writes_echo_log PROPERTIES FIXTURES_REQUIRED simulate_vineyard)
rowloc_cli_test(replay_echo_log_needs_map OFF "--echo-log needs --map"
                replay ${_logs}/vineyard-002-1us-echoes.ndjson --vehicle ${_ugv} --echo-log ${_replay_out}/x-echoes.ndjson
                -o ${_replay_out}/x.ndjson)
# --smoothed: the fixed-interval smoothed stream at the same times (docs/localization-filter.md §6),
# which rowloc evaluate reads like the filtered one; with wheel-angles.json on the tiles run.
rowloc_cli_test(replay_writes_smoothed_stream ON "smoothed\\.ndjson: [1-9][0-9]+ smoothed estimates over [1-9][0-9]+ filter nodes"
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/config/filters/wheel-angles.json
                -o ${_replay_out}/tiles-filtered.ndjson --smoothed ${_replay_out}/tiles-smoothed.ndjson)
set_tests_properties(apps.replay_writes_smoothed_stream PROPERTIES FIXTURES_REQUIRED simulate_tiles
                     FIXTURES_SETUP replay_smoothed)
rowloc_cli_test(replay_smoothed_stream_evaluates ON "position, total \\[m\\] +[0-9]+ +0\\.00[0-4]"
                evaluate ${_sim_out}/tiles-a/truth.ndjson ${_replay_out}/tiles-smoothed.ndjson --clip-to-truth
                -o ${_replay_out}/tiles-smoothed-report --no-plots)
rowloc_cli_reproducible_test(replay_smoothed_is_deterministic ${_replay_out}/tiles-smoothed-2.ndjson
                             ${_replay_out}/tiles-smoothed.ndjson
                             replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                             --filter ${PROJECT_SOURCE_DIR}/config/filters/wheel-angles.json
                             -o ${_replay_out}/tiles-filtered-2.ndjson --smoothed ${_replay_out}/tiles-smoothed-2.ndjson)
set_tests_properties(apps.replay_smoothed_stream_evaluates apps.replay_smoothed_is_deterministic
                     PROPERTIES FIXTURES_REQUIRED "simulate_tiles;replay_smoothed")
rowloc_cli_test(replay_rejects_smoothed_over_output OFF "--smoothed .*x.ndjson. is the same file as --output .*: two outputs cannot share a file"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve}
                -o ${_replay_out}/x.ndjson --smoothed ${_replay_out}/x.ndjson)
# --calibration: the wheel calibration of a previous drive (the smoothed tiles run above) as the prior;
# an estimate stream without one (the GNSS baseline) is refused.
rowloc_cli_test(replay_takes_a_calibration_prior ON "wheel calibration prior from .*tiles-smoothed\\.ndjson \\(t="
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/config/filters/wheel-angles.json
                --calibration ${_replay_out}/tiles-smoothed.ndjson -o ${_replay_out}/tiles-calibrated.ndjson)
set_tests_properties(apps.replay_takes_a_calibration_prior PROPERTIES FIXTURES_REQUIRED "simulate_tiles;replay_smoothed")
rowloc_cli_test(replay_rejects_a_stream_without_calibration OFF "no estimate with a wheel_calibration"
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                --calibration ${_sim_out}/tiles-a/baseline-gnss.ndjson -o ${_replay_out}/x.ndjson)
set_tests_properties(apps.replay_rejects_a_stream_without_calibration PROPERTIES FIXTURES_REQUIRED simulate_tiles)
rowloc_cli_test(replay_rejects_a_calibration_without_slip_states OFF "no slip-aware states"
                replay ${_sim_out}/tiles-a/sensors.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/config/filters/no-slip-model.json
                --calibration ${_replay_out}/tiles-smoothed.ndjson -o ${_replay_out}/x.ndjson)
set_tests_properties(apps.replay_rejects_a_calibration_without_slip_states
                     PROPERTIES FIXTURES_REQUIRED "simulate_tiles;replay_smoothed")
# Issue 26 (engineer "filter"): a torque of 1e308 once aborted the replay with no line or key; the
# log reader now refuses 1e308 itself, and a torque the reader accepts but no sensor produces (5e5 N m)
# is rejected by the filter with its line and key, and the run goes on. Filter values outside their physical
# range (a prediction step of 1e-300 s hung the filter; a sigma of 1e300 overflowed it) are refused
# at load with the key and the range in short numbers.
rowloc_cli_test(replay_rejects_huge_torque_by_line_and_key ON
                "huge-torque.ndjson:9: rejected: wheels at t=0.02 s: wheels.torque_nm.right = 500000 is outside \\[-100000, 100000\\].*1 rejected inputs"
                replay ${_logs}/agrimaro-tiles-huge-torque.ndjson --vehicle ${_swerve} -o ${_replay_out}/torque.ndjson)
rowloc_cli_test(replay_skips_a_line_the_reader_refuses ON
                "torque-1e308.ndjson:9: rejected: torque_nm.right: .*1 rejected inputs.*wrote"
                replay ${_logs}/agrimaro-tiles-torque-1e308.ndjson --vehicle ${_swerve} -o ${_replay_out}/torque-1e308.ndjson)
rowloc_cli_test(replay_rejects_tiny_prediction_step OFF
                "tiny-step.json: max_prediction_step_s must be in \\[0.0001, 1\\], got 1e-300"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/tests/data/filters/tiny-step.json -o ${_replay_out}/x.ndjson)
rowloc_cli_test(replay_rejects_huge_sigma OFF
                "huge-sigma.json: imu.gyro_sigma_radps must be in \\[1e-09, 100\\], got 1e\\+300"
                replay ${_logs}/agrimaro-tiles-head.ndjson --vehicle ${_swerve}
                --filter ${PROJECT_SOURCE_DIR}/tests/data/filters/huge-sigma.json -o ${_replay_out}/x.ndjson)
# Issue 29: without --filter, the filter the vehicle file recommends (recommended_filter). The
# differential recommends its own file (config/filters/differential.json): the replay says so and
# writes the bytes of a replay with that file given; with --filter the given file wins.
set(_diff_vehicle ${PROJECT_SOURCE_DIR}/config/vehicles/differential.json)
rowloc_cli_test(replay_simulates_a_differential_run ON "wrote"
                simulate ${_sim_scenarios}/slip-odometry-turns.json -o ${_sim_out}/turns --no-baselines)
set_tests_properties(apps.replay_simulates_a_differential_run PROPERTIES FIXTURES_SETUP simulate_turns)
rowloc_cli_test(replay_uses_the_recommended_filter ON
                "with vehicle differential and filter differential \\([^)]*filters/differential\\.json, recommended by [^)]*vehicles/differential\\.json\\)"
                replay ${_sim_out}/turns/sensors.ndjson --vehicle ${_diff_vehicle} -o ${_replay_out}/turns-recommended.ndjson)
set_tests_properties(apps.replay_uses_the_recommended_filter PROPERTIES FIXTURES_REQUIRED simulate_turns
                     FIXTURES_SETUP replay_recommended)
rowloc_cli_reproducible_test(replay_recommended_filter_is_the_file_given
                             ${_replay_out}/turns-given.ndjson ${_replay_out}/turns-recommended.ndjson
                             replay ${_sim_out}/turns/sensors.ndjson --vehicle ${_diff_vehicle}
                             --filter ${PROJECT_SOURCE_DIR}/config/filters/differential.json
                             -o ${_replay_out}/turns-given.ndjson)
set_tests_properties(apps.replay_recommended_filter_is_the_file_given PROPERTIES
                     FIXTURES_REQUIRED "simulate_turns;replay_recommended")
rowloc_cli_test(replay_given_filter_wins_over_the_recommended_one ON
                "with vehicle differential and filter default \\([^)]*filters/default\\.json\\)"
                replay ${_sim_out}/turns/sensors.ndjson --vehicle ${_diff_vehicle}
                --filter ${PROJECT_SOURCE_DIR}/config/filters/default.json -o ${_replay_out}/turns-default.ndjson)
set_tests_properties(apps.replay_given_filter_wins_over_the_recommended_one PROPERTIES FIXTURES_REQUIRED simulate_turns)
# A recommended filter that is missing is bad input (exit 2), named with the vehicle file.
add_test(NAME apps.replay_names_a_missing_recommended_filter
         COMMAND ${CMAKE_COMMAND}
                 "-DCOMMAND=$<TARGET_FILE:rowloc>;replay;${_logs}/agrimaro-tiles-head.ndjson;--vehicle;tests/data/vehicles/recommends-a-missing-filter.json;-o;${_replay_out}/x.ndjson"
                 -DEXPECT_SUCCESS=OFF -DEXPECT_STATUS=2
                 "-DEXPECT_STDERR=recommends-a-missing-filter\\.json: recommended_filter: tests/data/vehicles/\\.\\./filters/absent\\.json: cannot open filter file"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(apps.replay_names_a_missing_recommended_filter PROPERTIES LABELS apps)
