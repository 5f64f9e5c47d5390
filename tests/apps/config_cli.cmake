# CLI tests of 'rowloc config show' (docs/localization-filter.md §3): the complete values a filter
# file, a vehicle's filter choice or a scenario loads to, on stdout; which file was read, on stderr.
set(_config_filters ${PROJECT_SOURCE_DIR}/config/filters)
set(_config_vehicles ${PROJECT_SOURCE_DIR}/config/vehicles)
# Runs `rowloc config show ARGN` and matches its stdout and stderr separately.
function(rowloc_config_show_test name stdout_regex stderr_regex)
  string(JOIN ";" _command $<TARGET_FILE:rowloc> config show ${ARGN})
  add_test(NAME apps.config_show_${name}
           COMMAND ${CMAKE_COMMAND} "-DCOMMAND=${_command}" -DEXPECT_SUCCESS=ON "-DEXPECT_STDOUT=${stdout_regex}"
                   "-DEXPECT_STDERR=${stderr_regex}" -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(apps.config_show_${name} PROPERTIES LABELS apps)
endfunction()
# --vehicle: the filter the vehicle file recommends, every key (the differential's wheel sigma, the
# defaults' gps values).
rowloc_config_show_test(vehicle_prints_the_recommended_filter
  "^{[^,]*\"name\": \"differential\",.*\"sigma_floor_sbas_m\": 0\\.3,.*\"speed_sigma_radps\": 0\\.06345,.*\"max_time_jump_s\": 3600\\.0[^,]*}[^,]*$"
  "filter differential \\([^)]*filters/differential\\.json, recommended by [^)]*vehicles/differential\\.json\\)"
  --vehicle ${_config_vehicles}/differential.json)
# --vehicle with --filter: the given file, as `rowloc replay` would use it.
rowloc_config_show_test(vehicle_with_filter_prints_the_given_filter
  "^{[^,]*\"name\": \"wheel-angles\",.*\"speed_sigma_radps\": 0\\.1,"
  "filter wheel-angles \\([^)]*filters/wheel-angles\\.json\\)"
  --vehicle ${_config_vehicles}/differential.json --filter ${_config_filters}/wheel-angles.json)
rowloc_config_show_test(without_options_prints_the_defaults "^{[^,]*\"name\": \"default\","
  "filter default \\(the built-in defaults\\)")
rowloc_cli_test(config_show_vehicle_names_a_missing_recommended_filter OFF
  "recommends-a-missing-filter\\.json: recommended_filter: .*absent\\.json: cannot open filter file"
  config show --vehicle tests/data/vehicles/recommends-a-missing-filter.json)
rowloc_cli_test(config_show_scenario_is_alone OFF "--scenario shows a scenario: give it alone"
  config show --scenario config/scenarios/agrimaro-tiles.json --vehicle ${_config_vehicles}/differential.json)
