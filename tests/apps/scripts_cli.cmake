# Tests of the Python scripts under scripts/ that drive the rowloc command (`rowloc` built here).

# Runs `scripts/SCRIPT ARGN --rowloc <the built rowloc>` (rowloc_command_test, tests/CMakeLists.txt).
function(rowloc_script_test name expect_success regex script)
  rowloc_command_test(scripts.${name} ${expect_success} "${regex}" ${PROJECT_SOURCE_DIR}/scripts/${script} ${ARGN}
                      --rowloc $<TARGET_FILE:rowloc>)
endfunction()

set(_swerve --vehicle config/vehicles/agrimaro-swerve.json)
# One line per seed; a scenario that keeps its fixes has no final error after a loss.
rowloc_script_test(seed_sweep_tiles ON
  "\\| 1 \\| - \\| [0-9.]+ \\(2\\.62-3\\.40\\) \\| [0-9.]+ wheels .*\\| [0-9]+ % \\|.*\\| 2 \\| - \\| .*over 2 seeds.*never loses its absolute fixes.*odometry whiteness: median [0-9]+ % of lags inside their band, [0-2] of 2 seeds >= 95 %"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter config/filters/default.json --seeds 1-2)
# The whiteness control (docs/notes/2026-12-02-localization-filter.md §5.11): with an encoder whose speed error is
# white and the filter file with the simulated sensors' noises, the wheel innovations pass issue 4's
# test (>= 95 % of lags inside the band) on seed 12: 100 % (with the default file 94 %; with the
# 1024-tick encoder and the same file 10 %).
rowloc_script_test(seed_sweep_whiteness_control ON
  "odometry whiteness: median (9[5-9]|100) % of lags inside their band, 1 of 1 seeds >= 95 %"
  seed-sweep config/scenarios/agrimaro-tiles-white-encoder.json ${_swerve} --filter config/filters/white-encoder.json
  --seeds 12)
# A scenario that loses them: the final error, counted against the threshold.
rowloc_script_test(seed_sweep_turns ON
  "\\| 3 \\| 0\\.[0-9]+ \\| .* wheel_angles .*final error: median 0\\.[0-9]+ m, max 0\\.[0-9]+ m, [01] of 1 seeds <= 0\\.15 m"
  seed-sweep config/scenarios/slip-odometry-turns.json --vehicle config/vehicles/differential.json
  --filter config/filters/wheel-angles.json --seeds 3)
# --with-map: the map-aided update with each run's row map (vineyard: the ultrasonic NIS is in the
# report; the NEES near 3 where without the map it is 8).
rowloc_script_test(seed_sweep_with_the_row_map ON "\\| 1 \\| - \\| [1-4]\\.[0-9]+ \\(2\\.94-3\\.06\\) \\|.*over 1 seeds"
  seed-sweep config/scenarios/vineyard-002-4us.json --vehicle config/vehicles/vineyard-ugv-4ws.json
  --filter config/filters/default.json --seeds 1 --with-map)
rowloc_script_test(seed_sweep_with_map_needs_a_world OFF "--with-map: config/scenarios/agrimaro-tiles\\.json writes no row map"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter config/filters/default.json --seeds 1 --with-map)
rowloc_script_test(seed_sweep_rejects_empty_range OFF "seeds 3-1: the range is empty"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter config/filters/default.json --seeds 3-1)
rowloc_script_test(seed_sweep_rejects_missing_scenario OFF "no such file: config/scenarios/absent.json"
  seed-sweep config/scenarios/absent.json ${_swerve} --filter config/filters/default.json --seeds 1)
# A run that fails names its command and shows rowloc's error.
rowloc_script_test(seed_sweep_reports_a_failed_run OFF "seed-sweep: .*rowloc replay .*failed \\(2\\):.*bad-gate\\.json: .*gate_probability"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter tests/data/filters/bad-gate.json --seeds 1)

# tune-noise: the bisection finds the wheel sigma at which the differential's wheel NIS per dof is
# 1 on one training seed (loose tolerance: a few replays), and checks it on another.
set(_diff config/scenarios/slip-odometry-loops.json --vehicle config/vehicles/differential.json
    --filter config/filters/default.json)
rowloc_script_test(tune_noise_identifies_the_wheel_sigma ON
  "identified: wheels\\.speed_sigma_radps = 0\\.06[0-9]* \\(file: 0\\.1; factor 0\\.6[0-9]*\\).*slip-odometry-loops\\.json \\| 2 \\| 0\\.9[0-9]+ -> [12]\\.[0-9]+ .*identified: NIS per dof (0\\.9[5-9]|1\\.0[0-5])"
  tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor wheels --train 1 --test 2 --low 0.5 --high 0.8
  --tolerance 0.05 -o ${CMAKE_CURRENT_BINARY_DIR}/tuned-wheels.json)
# -o writes an overlay on the defaults: the name and the one key that differs from them, nothing else.
add_test(NAME scripts.tune_noise_writes_an_overlay
         COMMAND ${CMAKE_COMMAND} -DFILE=${CMAKE_CURRENT_BINARY_DIR}/tuned-wheels.json
                 "-DPATTERN=^[{][^,]*\"name\": \"tuned-wheels\",[^,]*\"wheels\": [{][^,]*\"speed_sigma_radps\": 0\\.06[0-9]*[^,]*$"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/file_contains.cmake)
set_tests_properties(scripts.tune_noise_identifies_the_wheel_sigma PROPERTIES FIXTURES_SETUP tune_wheels)
set_tests_properties(scripts.tune_noise_writes_an_overlay PROPERTIES LABELS "apps;sweep" FIXTURES_REQUIRED tune_wheels)
rowloc_script_test(tune_noise_rejects_an_interval_that_does_not_bracket OFF
  "factor \\[1, 2\\] of wheels\\.speed_sigma_radps does not bracket NIS per dof 1: 0\\.4[0-9]+ at 1"
  tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor wheels --train 1 --test 2 --low 1 --high 2)
rowloc_script_test(tune_noise_rejects_an_absent_key OFF "default\\.json: wheels\\.speed_sigma is not a number > 0 in the filter"
  tune-noise ${_diff} --key wheels.speed_sigma --sensor wheels --train 1 --test 2)
rowloc_script_test(tune_noise_rejects_overlapping_seeds OFF "--train and --test seeds overlap"
  tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor wheels --train 1-3 --test 3-4)
rowloc_script_test(tune_noise_names_a_sensor_without_updates OFF
  "seed 1: no 'ultrasonic' updates \\(the run has: gnss, imu, nonholonomic, wheels\\)"
  tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor ultrasonic --train 1 --test 2)
# --with-map: the range sigma of a rough canopy from the ultrasonic NIS (the echoes are updates only
# with the row map); seed 1's NIS per dof is 1.12 at 1.1 x 3 mm and 0.59 at 1.6 x. The filter keeps
# the range sigma fixed (without it the filter estimates it online and the key is only its floor).
rowloc_script_test(tune_noise_identifies_the_range_sigma_with_the_map ON
  "identified: map_aided\\.range_sigma_m = 0\\.003[4-8][0-9]* \\(file: 0\\.003; .*vineyard-002-rough-4us\\.json \\| 2 \\| 1\\.[0-9]+ -> (0\\.9|1\\.0)[0-9]+ "
  tune-noise config/scenarios/vineyard-002-rough-4us.json --vehicle config/vehicles/vineyard-ugv-4ws.json
  --filter tests/data/filters/fixed-range-sigma.json --key map_aided.range_sigma_m --sensor ultrasonic --with-map
  --train 1 --test 2 --low 1.1 --high 1.6 --tolerance 0.1)
rowloc_script_test(tune_noise_with_map_needs_a_world OFF
  "tune-noise: --with-map: config/scenarios/slip-odometry-loops\\.json writes no row map"
  tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor wheels --train 1 --test 2 --with-map)
# A NIS that jumps across 1 (a stand-in rowloc whose wheel NIS per dof is 1.5 below 0.05 rad/s and
# 0.5 above) has no match: the bisection says where it jumps instead of returning a value.
rowloc_command_test(scripts.tune_noise_reports_a_jump_it_cannot_match OFF
  "the NIS per dof jumps from 1\\.5000 to 0\\.5000 between factors 0\\.499[0-9]* and 0\\.50*: no value matches"
  ${PROJECT_SOURCE_DIR}/scripts/tune-noise ${_diff} --key wheels.speed_sigma_radps --sensor wheels --train 1 --test 2
  --rowloc ${PROJECT_SOURCE_DIR}/tests/data/fake-rowloc-nis-step)

# validate-sim --seeds: the scenario's replays, then the seed sweeps of the default filter and of the
# vehicle's own file (the differential has one) in one table.
rowloc_command_test(scripts.validate_sim_sweeps_seeds ON
  "\\| slip-odometry-turns \\| default \\| [0-9.]+ / [0-9.]+ \\| [0-2] of 2 \\| 0\\.[0-9]+ / [0-9.]+ \\| [0-2] of 2 \\| 0\\.9[0-9] \\(wheels\\) \\|.*\\| slip-odometry-turns \\| differential \\| .* \\| 1\\.9[0-9] \\(wheels\\) \\|"
  ${PROJECT_SOURCE_DIR}/scripts/validate-sim --seeds 1-2 $<TARGET_FILE:rowloc> ${CMAKE_CURRENT_BINARY_DIR}/validate-seeds
  slip-odometry-turns)
# A scenario that names filter files ("filters"): validate-sim replays each (the summary's
# ekf-file-<name> row) and sweeps it over the seeds, with the odometry whiteness in the table.
rowloc_command_test(scripts.validate_sim_runs_the_scenario_filters ON
  "\\| agrimaro-tiles-white-encoder \\| ekf-file-white-encoder \\| .*\\| agrimaro-tiles-white-encoder \\| white-encoder \\| [0-9.]+ / [0-9.]+ \\| [01] of 1 \\| n/a \\| n/a \\| [0-9.]+ \\(wheels\\) \\| (9[5-9]|100) % \\(1 of 1\\) \\|"
  ${PROJECT_SOURCE_DIR}/scripts/validate-sim --seeds 1 $<TARGET_FILE:rowloc> ${CMAKE_CURRENT_BINARY_DIR}/validate-filters
  agrimaro-tiles-white-encoder)
rowloc_command_test(scripts.validate_sim_rejects_an_empty_seed_range OFF "validate-sim: seeds 3-1: the range is empty"
  ${PROJECT_SOURCE_DIR}/scripts/validate-sim --seeds 3-1 $<TARGET_FILE:rowloc> ${CMAKE_CURRENT_BINARY_DIR}/validate-seeds-bad
  slip-odometry-turns)
rowloc_command_test(scripts.validate_sim_rejects_malformed_seeds OFF "validate-sim: --seeds must be N or N-M \\(e\\.g\\. 1-12\\), got '1,2'"
  ${PROJECT_SOURCE_DIR}/scripts/validate-sim --seeds 1,2 $<TARGET_FILE:rowloc> ${CMAKE_CURRENT_BINARY_DIR}/validate-seeds-bad
  slip-odometry-turns)

# tools/ratio-scale-walk (a research tool, no rowloc): over 30 s the exact posterior of R walks up with the EKF and the
# unscented update (0.254 -> 0.270 m on seed 1), the iterated update walks down; without the
# speed noise nothing walks.
set(_walk ${PROJECT_SOURCE_DIR}/tools/ratio-scale-walk --seeds 1 --duration 30)
rowloc_command_test(tools.ratio_scale_walk_exact_posterior_walks ON
  "\\| ekf \\| 0\\.2[6-9][0-9]+ .*\\| ukf \\| 0\\.2[6-9][0-9]+ .*\\| iekf \\| 0\\.(1|2[0-4])[0-9]+ .*\\| exact \\| 0\\.2[6-9][0-9]+ "
  ${_walk})
rowloc_command_test(tools.ratio_scale_walk_without_speed_noise_stays ON
  "\\| ekf \\| 0\\.25[0-5][0-9] .*\\| exact \\| 0\\.25[0-5][0-9] "
  ${_walk} --speed-noise 0)
rowloc_command_test(tools.ratio_scale_walk_rejects_empty_range OFF "empty seed range: 3-1"
  ${PROJECT_SOURCE_DIR}/tools/ratio-scale-walk --seeds 3-1)
rowloc_command_test(tools.ratio_scale_walk_rejects_a_zero_duration OFF
  "--duration and --true-radius must be > 0, --speed-noise >= 0"
  ${PROJECT_SOURCE_DIR}/tools/ratio-scale-walk --duration 0)

# The statistical sweeps run the filter many times over whole scenarios: they measure the tools'
# results, not new code paths (every path they take is also run once by the apps tests). Label
# "sweep": the sanitizer pass skips them (CMakePresets.json, preset asan), where they would take
# about 8 minutes of the CI's 45.
set_property(TEST scripts.tune_noise_identifies_the_range_sigma_with_the_map scripts.validate_sim_sweeps_seeds
             scripts.seed_sweep_with_the_row_map scripts.tune_noise_identifies_the_wheel_sigma
             APPEND PROPERTY LABELS sweep)

# The map build's quality table on one world, with its scan defects (docs/mapping.md): every part
# found within 2 cm, and a map with meshes; and the built map in the map-aided filter on one
# scenario (the table's ratio is reported, not required: docs/mapping.md "End to end").
rowloc_script_test(map_quality_gappy_with_outliers ON
  "\\| gappy-outliers \\| 5 / 5 \\| 10 / 10 \\| 0 / 0 \\| 0\\.[0-9]+ \\| [0-9.]+ \\|.*\\| [0-9]+ / [0-9.]+ \\| [0-9]+ \\|"
  map-quality --out ${CMAKE_CURRENT_BINARY_DIR}/map-quality --require-p95 0.02 --survey "--survey-outliers 0.01"
  --label outliers gappy)
rowloc_script_test(map_quality_rejects_an_unknown_world OFF "config/worlds/nowhere\\.json"
  map-quality --out ${CMAKE_CURRENT_BINARY_DIR}/map-quality-bad nowhere)
rowloc_script_test(map_end_to_end_straight_rows ON
  "\\| vineyard-002-4us \\| 6 \\| [0-9.]+ / [0-9.]+ \\| [0-9.]+ / [0-9.]+ \\| [0-9.]+ \\| [0-9.]+ / [0-9.]+ \\|"
  map-end-to-end --out ${CMAKE_CURRENT_BINARY_DIR}/map-end-to-end vineyard-002-4us)
rowloc_script_test(map_end_to_end_rejects_an_unknown_scenario OFF "no scenario .*nowhere\\.json"
  map-end-to-end --out ${CMAKE_CURRENT_BINARY_DIR}/map-end-to-end-bad nowhere)
