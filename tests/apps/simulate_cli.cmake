# CLI tests of 'rowloc simulate' (docs/simulation-scenarios.md).
set(_sim_scenarios ${PROJECT_SOURCE_DIR}/config/scenarios)
set(_sim_out ${CMAKE_CURRENT_BINARY_DIR}/simulate)
rowloc_cli_test(simulate_runs_open_field ON "20\\.0 s simulated \\(15\\.0 m\\).*4204 sensor messages"
                simulate ${_sim_scenarios}/agrimaro-tiles.json -o ${_sim_out}/tiles-a)
rowloc_cli_test(simulate_runs_vineyard ON "true row map at 1 m.*ultrasonic [0-9]+ echoes"
                simulate ${_sim_scenarios}/vineyard-002-1us.json -o ${_sim_out}/vineyard --no-baselines)
rowloc_cli_test(simulate_rejects_missing_scenario OFF "scenario .no-such-scenario.json.: no such file"
                simulate no-such-scenario.json -o ${_sim_out}/missing)
rowloc_cli_test(simulate_rejects_bad_seed OFF "seed"
                simulate ${_sim_scenarios}/agrimaro-tiles.json -o ${_sim_out}/bad-seed --seed -3)
set_tests_properties(apps.simulate_runs_open_field PROPERTIES FIXTURES_SETUP simulate_tiles)
# Same scenario and seed, same bytes: a second run into another directory.
rowloc_cli_reproducible_test(simulate_is_deterministic ${_sim_out}/tiles-a/sensors.ndjson ${_sim_out}/tiles-b/sensors.ndjson
                             simulate ${_sim_scenarios}/agrimaro-tiles.json -o ${_sim_out}/tiles-b)
# The simulator's streams are accepted by the evaluator (the baseline GNSS estimate of the first run).
rowloc_cli_test(simulate_output_evaluates ON "position, total \\[m\\] +201 "
                evaluate ${_sim_out}/tiles-a/truth.ndjson ${_sim_out}/tiles-a/baseline-gnss.ndjson
                -o ${_sim_out}/tiles-a-report --no-plots)
set_tests_properties(apps.simulate_is_deterministic apps.simulate_output_evaluates
                     PROPERTIES FIXTURES_REQUIRED simulate_tiles)
