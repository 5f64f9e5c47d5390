# CLI tests of 'rowloc calibrate' (docs/calibration.md): a simulated one-lane drive replayed with a
# vehicle file whose front-left ranger is written 5 cm off; the calibration finds it, writes a
# vehicle file that `rowloc replay` reads; clear errors for bad input.
set(_cal_out ${CMAKE_CURRENT_BINARY_DIR}/calibrate)
set(_cal_data ${PROJECT_SOURCE_DIR}/tests/data/calibration)
set(_cal_vehicle ${_cal_data}/vineyard-ugv-4ws-front-left-5cm-out.json)
file(MAKE_DIRECTORY ${_cal_out})
rowloc_cli_test(calibrate_simulates_one_lane ON "wrote"
                simulate ${_cal_data}/one-lane.json -o ${_cal_out}/one-lane --no-baselines)
set_tests_properties(apps.calibrate_simulates_one_lane PROPERTIES FIXTURES_SETUP simulate_one_lane)
rowloc_cli_test(calibrate_finds_the_mount_error ON
                "us_front_left +[0-9]+ +-(4[5-9]|5[0-4])\\.[0-9].*wrote .*calibrated-vehicle.json"
                calibrate ${_cal_out}/one-lane/sensors.ndjson --vehicle ${_cal_vehicle}
                --map ${_cal_out}/one-lane/row-map.geojson -o ${_cal_out}/report.json
                --write-vehicle ${_cal_out}/calibrated-vehicle.json)
set_tests_properties(apps.calibrate_finds_the_mount_error PROPERTIES FIXTURES_REQUIRED simulate_one_lane
                     FIXTURES_SETUP calibrated_vehicle)
add_test(NAME apps.calibrate_report_and_vehicle
         COMMAND ${CMAKE_COMMAND} -DREPORT=${_cal_out}/report.json -DVEHICLE=${_cal_out}/calibrated-vehicle.json
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/calibrate_check.cmake)
set_tests_properties(apps.calibrate_report_and_vehicle PROPERTIES LABELS apps FIXTURES_REQUIRED calibrated_vehicle)
# The written vehicle file is a vehicle file: the map-aided replay reads it.
rowloc_cli_test(calibrate_vehicle_replays ON "map-aided \\(range\\): [0-9]+ echoes"
                replay ${_cal_out}/one-lane/sensors.ndjson --vehicle ${_cal_out}/calibrated-vehicle.json
                --map ${_cal_out}/one-lane/row-map.geojson -o ${_cal_out}/replay.ndjson)
set_tests_properties(apps.calibrate_vehicle_replays PROPERTIES FIXTURES_REQUIRED "simulate_one_lane;calibrated_vehicle")
# Bad input: a clear error, exit status 2.
rowloc_cli_test(calibrate_rejects_missing_map OFF "--map .no-such-map.geojson.: no such file"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${_cal_vehicle} --map no-such-map.geojson -o ${_cal_out}/x.json)
rowloc_cli_test(calibrate_rejects_a_vehicle_without_rangers OFF "no ultrasonic sensor to calibrate"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${PROJECT_SOURCE_DIR}/config/vehicles/agrimaro-swerve.json
                --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson -o ${_cal_out}/x.json)
rowloc_cli_test(calibrate_rejects_a_drive_too_short OFF "never initialised"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${_cal_vehicle} --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson -o ${_cal_out}/x.json)
rowloc_cli_test(calibrate_rejects_an_unknown_setting OFF "bad-key.json: range_sigma: unknown key"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${_cal_vehicle} --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson
                --config ${_cal_data}/bad-key.json -o ${_cal_out}/x.json)
rowloc_cli_test(calibrate_refuses_to_overwrite_its_log OFF "--output .* is the same file as the input log"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${_cal_vehicle} --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson
                -o ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson)
# tools/mount-sweep (a research tool) on the one-lane drive: the calibration's error and the check's
# report per case; an unknown case is refused.
rowloc_command_test(tools.mount_sweep_measures_a_case ON
  "\\| 2 \\| right \\| [0-2]\\.[0-9] \\| 0\\.0 \\| - \\|.*\\| 2 \\| FLout5 \\| [0-4]\\.[0-9] \\| 0\\.0 \\| us_front_left \\([0-9.]+\\) \\|"
  ${PROJECT_SOURCE_DIR}/tools/mount-sweep ${_cal_data}/one-lane.json --seeds 2 --cases right,FLout5 --check
  --rowloc $<TARGET_FILE:rowloc> --out ${_cal_out}/mount-sweep)
rowloc_command_test(tools.mount_sweep_rejects_an_unknown_case OFF "unknown case sideways"
  ${PROJECT_SOURCE_DIR}/tools/mount-sweep ${_cal_data}/one-lane.json --cases sideways --rowloc $<TARGET_FILE:rowloc>)
# The settings are read as every configuration file is (mapio::ReadInputFile): a device that never
# ends is refused before a byte is read.
rowloc_cli_test(calibrate_refuses_an_endless_settings_file OFF "/dev/zero: is a character device, not a regular file"
                calibrate ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson
                --vehicle ${_cal_vehicle} --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson
                --config /dev/zero -o ${_cal_out}/x.json)
