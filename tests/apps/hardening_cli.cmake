# CLI tests of issue 26 ("hardening"): one exit-status rule for every command (0 success, 2 bad
# input, 1 internal failure), results on stdout and logs on stderr, no output that destroys an
# input or replaces a non-regular file, and point cloud headers checked against the file.
set(_h ${CMAKE_CURRENT_BINARY_DIR}/hardening)
file(MAKE_DIRECTORY ${_h})
set(_swerve ${PROJECT_SOURCE_DIR}/config/vehicles/agrimaro-swerve.json)
set(_head_log ${PROJECT_SOURCE_DIR}/tests/data/logs/agrimaro-tiles-head.ndjson)
set(_sample ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson)
set(_a_dir ${PROJECT_SOURCE_DIR}/tests/data)

# rowloc_cli_status_test(NAME STATUS STDERR_REGEX ARGS...): `rowloc ARGS` exits with STATUS, says
# STDERR_REGEX on stderr, and prints nothing on stdout.
function(rowloc_cli_status_test name status regex)
  string(JOIN ";" _command $<TARGET_FILE:rowloc> ${ARGN})
  add_test(NAME apps.${name}
           COMMAND ${CMAKE_COMMAND} "-DCOMMAND=${_command}" -DEXPECT_SUCCESS=OFF -DEXPECT_STATUS=${status}
                   "-DEXPECT_STDERR=${regex}" -DEXPECT_EMPTY_STDOUT=ON -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(apps.${name} PROPERTIES LABELS apps)
endfunction()
# rowloc_cli_keeps_input_test(NAME ORIGINAL COPY REGEX ARGS...): COPY (a fresh copy of ORIGINAL) is
# named as an output of `rowloc ARGS`: refused with exit 2 and REGEX on stderr, COPY unchanged.
function(rowloc_cli_keeps_input_test name original copy regex)
  string(JOIN ";" _command $<TARGET_FILE:rowloc> ${ARGN})
  add_test(NAME apps.${name}
           COMMAND ${CMAKE_COMMAND} -DORIGINAL=${original} -DCOPY=${copy} "-DCOMMAND=${_command}"
                   "-DEXPECT_OUTPUT=${regex}" ${_keeps_input_extra} -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/keeps_input.cmake
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(apps.${name} PROPERTIES LABELS apps)
endfunction()

# --- exit statuses: a bad option and a bad input file for every command (before: 105/106 and 1) ---
rowloc_cli_status_test(exit_unknown_command 2 "A subcommand is required" bogus)
rowloc_cli_status_test(exit_example_bad_option 2 "--bogus" example --map ${_sample} --bogus)
rowloc_cli_status_test(exit_example_bad_map 2 "--map" example --map ${_h}/no-such.geojson)
rowloc_cli_status_test(exit_map_sample_bad_option 2 "--rows" map sample -o ${_h}/s.geojson --rows many)
rowloc_cli_status_test(exit_map_sample_missing_option 2 "--output is required" map sample)
rowloc_cli_status_test(exit_map_sample_refuses_a_directory 2 "is a directory; only a regular file is ever replaced"
                       map sample -o ${_h})
rowloc_cli_status_test(exit_map_info_bad_option 2 "--bogus" map info ${_sample} --bogus)
rowloc_cli_status_test(exit_map_info_missing_file 2 "map info: file '.*no-such\\.geojson': no such file"
                       map info ${_h}/no-such.geojson)
# A directory where a file is expected: said so, not "invalid JSON".
rowloc_cli_status_test(exit_map_info_directory 2 "file '.*tests/data': is a directory, expected a file" map info ${_a_dir})
rowloc_cli_status_test(exit_map_edit_bad_option 2 "--shift" map edit ${_sample} -o ${_h}/e.geojson --shift 1)
rowloc_cli_status_test(exit_map_edit_directory 2 "is a directory, expected a file" map edit ${_a_dir} -o ${_h}/e.geojson)
rowloc_cli_status_test(exit_map_build_bad_option 2 "--octomap: '-1' is not a finite number > 0"
                       map build x.pcd -o ${_h}/b --origin 45 7 240 --octomap -1)
rowloc_cli_status_test(exit_map_build_directory 2 "survey '.*tests/data': is a directory"
                       map build ${_a_dir} -o ${_h}/b --origin 45 7 240)
rowloc_cli_status_test(exit_map_compare_bad_option 2 "--step: 'nan' is not a finite number > 0"
                       map compare ${_sample} ${_sample} --step nan)
rowloc_cli_status_test(exit_map_compare_directory 2 "truth '.*tests/data': is a directory" map compare ${_sample} ${_a_dir})
rowloc_cli_status_test(exit_cloud_info_bad_option 2 "--bogus" cloud info x.ply --bogus)
rowloc_cli_status_test(exit_cloud_info_bad_file 2 "cloud info: point cloud .*empty\\.pcd"
                       cloud info ${PROJECT_SOURCE_DIR}/tests/data/mapping/empty.pcd)
# The range in the message is short (before: 309 digits of DBL_MAX).
rowloc_cli_status_test(exit_cloud_octomap_bad_resolution 2 "--resolution: -1 is not in \\[0\\.0001, 1000\\]\n"
                       cloud octomap x.ply ${_h}/x.bt --resolution -1)
rowloc_cli_status_test(exit_cloud_octomap_missing_input 2 "cloud octomap: input '.*no-such\\.ply': no such file"
                       cloud octomap ${_h}/no-such.ply ${_h}/x.bt)
rowloc_cli_status_test(exit_world_bad_option 2 "--step: 0 is not in \\[0\\.0001, 10\\]"
                       world ${PROJECT_SOURCE_DIR}/config/worlds/gappy.json -o ${_h}/w --step 0)
rowloc_cli_status_test(exit_world_directory 2 "world: world '.*tests/data': is a directory" world ${_a_dir} -o ${_h}/w)
rowloc_cli_status_test(exit_simulate_bad_option 2 "--seed" simulate x.json -o ${_h}/s --seed minus)
rowloc_cli_status_test(exit_simulate_directory 2 "simulate: scenario '.*tests/data': is a directory"
                       simulate ${_a_dir} -o ${_h}/s)
rowloc_cli_status_test(exit_evaluate_bad_option 2 "--k-sigma" evaluate a b -o ${_h}/ev --k-sigma 0)
rowloc_cli_status_test(exit_evaluate_directory 2 "evaluate: truth '.*tests/data': is a directory"
                       evaluate ${_a_dir} ${_head_log} -o ${_h}/ev)
rowloc_cli_status_test(exit_replay_bad_option 2 "--period" replay ${_head_log} --vehicle ${_swerve} -o ${_h}/r.ndjson
                       --period -1)
rowloc_cli_status_test(exit_replay_directory 2 "replay: --vehicle '.*tests/data': is a directory"
                       replay ${_head_log} --vehicle ${_a_dir} -o ${_h}/r.ndjson)
rowloc_cli_status_test(exit_send_bad_option 2 "--period" send ${_head_log} --vehicle v -o ${_h}/s.ndjson --period 0)
rowloc_cli_status_test(exit_send_missing_log 2 "send: log '.*no-such\\.ndjson': no such file"
                       send ${_h}/no-such.ndjson --vehicle v -o ${_h}/s.ndjson)
rowloc_cli_status_test(exit_serve_bad_option 2 "--bogus" serve --bogus)
# serve's numbers are checked as the others' are, naming the option and its range (before: "settings:
# port: must be in ..." or "Could not convert: --port = 99999999999").
rowloc_cli_status_test(exit_serve_bad_port 2 "--port: 70000 is not in \\[0, 65535\\]\n" serve --port 70000)
rowloc_cli_status_test(exit_serve_huge_port 2 "--port: 99999999999 is not in \\[0, 65535\\]\n" serve --port 99999999999)
rowloc_cli_status_test(exit_serve_bad_threads 2 "--threads: 0 is not in \\[1, 64\\]\n" serve --threads 0)
rowloc_cli_status_test(exit_serve_bad_http_port 2 "--http-port: 'x' is not a whole number\n" serve --http-port x)
rowloc_cli_test(exit_help_is_success ON "Usage:" map info --help)

# --- stdout carries results only, logs go to stderr ---
add_test(NAME apps.stdout_map_sample_logs_on_stderr
         COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:rowloc>;map;sample;-o;${_h}/sample.geojson"
                 -DEXPECT_SUCCESS=ON -DEXPECT_EMPTY_STDOUT=ON "-DEXPECT_STDERR=wrote 10 rows"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake)
add_test(NAME apps.stdout_map_info_result_on_stdout
         COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:rowloc>;map;info;${_sample}"
                 -DEXPECT_SUCCESS=ON "-DEXPECT_STDOUT=rows: 10, segments: " "-DEXPECT_STDERR=^$"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake)
add_test(NAME apps.stdout_replay_logs_on_stderr
         COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:rowloc>;replay;${_head_log};--vehicle;${_swerve};-o;${_h}/r.ndjson"
                 -DEXPECT_SUCCESS=ON -DEXPECT_EMPTY_STDOUT=ON "-DEXPECT_STDERR=messages, [0-9]+ estimates"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/run_cli.cmake)
set_tests_properties(apps.stdout_map_sample_logs_on_stderr apps.stdout_map_info_result_on_stdout
                     apps.stdout_replay_logs_on_stderr PROPERTIES LABELS apps)

# --- an output naming an input is refused before anything is opened, the input intact ---
rowloc_cli_keeps_input_test(keeps_replay_log_as_output ${_head_log} ${_h}/log-o.ndjson
                            "replay: --output '.*log-o\\.ndjson' is the same file as the input log"
                            replay ${_h}/log-o.ndjson --vehicle ${_swerve} -o ${_h}/log-o.ndjson)
rowloc_cli_keeps_input_test(keeps_replay_log_as_smoothed ${_head_log} ${_h}/log-s.ndjson
                            "--smoothed '.*log-s\\.ndjson' is the same file as the input log"
                            replay ${_h}/log-s.ndjson --vehicle ${_swerve} -o ${_h}/r-s.ndjson --smoothed ${_h}/log-s.ndjson)
rowloc_cli_keeps_input_test(keeps_replay_map_as_output ${_sample} ${_h}/map-o.geojson
                            "--output '.*map-o\\.geojson' is the same file as the input --map"
                            replay ${_head_log} --vehicle ${_swerve} --map ${_h}/map-o.geojson -o ${_h}/map-o.geojson)
rowloc_cli_keeps_input_test(keeps_replay_map_as_echo_log ${_sample} ${_h}/map-e.geojson
                            "--echo-log '.*map-e\\.geojson' is the same file as the input --map"
                            replay ${_head_log} --vehicle ${_swerve} --map ${_h}/map-e.geojson -o ${_h}/r-e.ndjson
                            --echo-log ${_h}/map-e.geojson)
rowloc_cli_keeps_input_test(keeps_replay_vehicle_as_output ${_swerve} ${_h}/vehicle-o.json
                            "--output '.*vehicle-o\\.json' is the same file as the input --vehicle"
                            replay ${_head_log} --vehicle ${_h}/vehicle-o.json -o ${_h}/vehicle-o.json)
set(_keeps_input_extra -DLINK=${_h}/log-link.ndjson)
rowloc_cli_keeps_input_test(keeps_replay_log_through_a_symlink ${_head_log} ${_h}/log-l.ndjson
                            "--output '.*log-link\\.ndjson' is the same file as the input log"
                            replay ${_h}/log-l.ndjson --vehicle ${_swerve} -o ${_h}/log-link.ndjson)
set(_keeps_input_extra)
rowloc_cli_keeps_input_test(keeps_map_edit_input ${_sample} ${_h}/edit.geojson "is the same file as the input file"
                            map edit ${_h}/edit.geojson -o ${_h}/edit.geojson --shift 1 1)
rowloc_cli_keeps_input_test(keeps_map_compare_input ${_sample} ${_h}/compare.geojson
                            "--json '.*compare\\.geojson' is the same file as the input built"
                            map compare ${_h}/compare.geojson ${_sample} --json ${_h}/compare.geojson)
rowloc_cli_keeps_input_test(keeps_send_log ${_head_log} ${_h}/send.ndjson "is the same file as the input log"
                            send ${_h}/send.ndjson --to 127.0.0.1:9 --vehicle v -o ${_h}/send.ndjson)
add_test(NAME apps.map_sample_refuses_a_fifo
         COMMAND ${CMAKE_COMMAND} -DFIFO=${_h}/fifo.geojson
                 "-DCOMMAND=$<TARGET_FILE:rowloc>;map;sample;-o;${_h}/fifo.geojson"
                 "-DEXPECT_OUTPUT=is a FIFO \\(named pipe\\); only a regular file is ever replaced"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/refuses_special.cmake)
set_tests_properties(apps.map_sample_refuses_a_fifo PROPERTIES LABELS apps)

# --- inputs read line by line: a line is refused once 1 MiB of it is read, never held whole ---
# Before: /dev/zero as an evaluate input, a --calibration stream or a send log took GBs (std::getline);
# send took a FIFO or /dev/zero as --vehicle for a name on the server, and crashed (exit 139) on a
# vehicle file nested 10^6 levels deep.
set(_eval_data ${PROJECT_SOURCE_DIR}/tests/data/evaluate)
rowloc_cli_status_test(evaluate_refuses_an_endless_truth_line 2 "evaluate: /dev/zero:1: line longer than 1 MiB"
                       evaluate /dev/zero ${_eval_data}/estimates.ndjson -o ${_h}/ev-zero --no-plots)
rowloc_cli_status_test(evaluate_refuses_an_endless_estimate_line 2 "evaluate: /dev/zero:1: line longer than 1 MiB"
                       evaluate ${_eval_data}/truth.ndjson /dev/zero -o ${_h}/ev-zero --no-plots)
rowloc_cli_status_test(replay_refuses_an_endless_calibration_line 2 "replay: /dev/zero:1: line longer than 1 MiB"
                       replay ${_head_log} --vehicle ${_swerve} --calibration /dev/zero -o ${_h}/r-zero.ndjson)
rowloc_cli_status_test(send_refuses_an_endless_log_line 2
                       "send: /dev/zero:1: line: longer than 1 MiB \\(1048576 bytes, the protocol's limit\\)"
                       send /dev/zero --to 127.0.0.1:9 --vehicle v -o ${_h}/s-zero.ndjson)
rowloc_cli_status_test(send_refuses_a_device_as_vehicle_file 2 "send: /dev/zero: is a character device, not a regular file"
                       send ${_head_log} --to 127.0.0.1:9 --vehicle /dev/zero -o ${_h}/s-zero.ndjson)
string(REPEAT "[" 1000000 _open)
string(REPEAT "]" 1000000 _close)
file(WRITE ${_h}/deep-vehicle.json "{\"name\":${_open}${_close}}")
rowloc_cli_status_test(send_refuses_a_deeply_nested_vehicle_file 2
                       "send: .*deep-vehicle\\.json: nested deeper than 64 levels of arrays and objects"
                       send ${_head_log} --to 127.0.0.1:9 --vehicle ${_h}/deep-vehicle.json -o ${_h}/s-deep.ndjson)
# Before the fix these took memory until killed: stop them well before that.
set_tests_properties(apps.evaluate_refuses_an_endless_truth_line apps.evaluate_refuses_an_endless_estimate_line
                     apps.replay_refuses_an_endless_calibration_line apps.send_refuses_an_endless_log_line
                     PROPERTIES TIMEOUT 30)
add_test(NAME apps.send_refuses_a_fifo_as_vehicle_file
         COMMAND ${CMAKE_COMMAND} -DFIFO=${_h}/vehicle-fifo.json
                 "-DCOMMAND=$<TARGET_FILE:rowloc>;send;${_head_log};--to;127.0.0.1:9;--vehicle;${_h}/vehicle-fifo.json;-o;${_h}/s-fifo.ndjson"
                 "-DEXPECT_OUTPUT=vehicle-fifo\\.json: is a FIFO \\(named pipe\\), not a regular file"
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/apps/refuses_special.cmake)
set_tests_properties(apps.send_refuses_a_fifo_as_vehicle_file PROPERTIES LABELS apps TIMEOUT 30)

# --- point clouds: header claims checked against the file (before: GBs, bad_alloc, zeros) ---
set(_pcd_head "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n")
file(WRITE ${_h}/count.pcd "${_pcd_head}COUNT 1000000000 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n")
file(WRITE ${_h}/points.pcd "${_pcd_head}COUNT 1 1 1\nWIDTH 50000000\nHEIGHT 1\nPOINTS 50000000\nDATA binary\n")
file(WRITE ${_h}/points.ply "ply\nformat binary_little_endian 1.0\nelement vertex 50000000\nproperty float x\n"
                            "property float y\nproperty float z\nend_header\n")
file(WRITE ${_h}/short.pcd "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                           "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n")
rowloc_cli_status_test(cloud_refuses_a_huge_count 2 "count\\.pcd': line 5: COUNT" cloud info ${_h}/count.pcd)
rowloc_cli_status_test(cloud_refuses_points_without_data_pcd 2 "POINTS 50000000 x 12 bytes needs 600000000 bytes"
                       cloud info ${_h}/points.pcd)
rowloc_cli_status_test(cloud_refuses_points_without_data_ply 2 "needs 600000000 bytes of data, but only 0"
                       cloud info ${_h}/points.ply)
rowloc_cli_status_test(cloud_refuses_a_short_ascii_line 2 "short\\.pcd': line 10: 3 values, but FIELDS and COUNT announce 4"
                       cloud info ${_h}/short.pcd)
file(WRITE ${_h}/cloud.ply "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                           "property float z\nend_header\n0 0 0\n1 1 1\n")
rowloc_cli_keeps_input_test(keeps_cloud_octomap_input ${_h}/cloud.ply ${_h}/cloud-o.ply
                            "output '.*cloud-o\\.ply' is the same file as the input input"
                            cloud octomap ${_h}/cloud-o.ply ${_h}/cloud-o.ply)
# example --plot DIR writes DIR/rows.dat, ...: the map given as --map may not be one of them.
file(MAKE_DIRECTORY ${_h}/plot)
rowloc_cli_keeps_input_test(keeps_example_map_in_plot_dir ${_sample} ${_h}/plot/rows.dat
                            "--plot '.*rows\\.dat' is the same file as the input --map"
                            example --map ${_h}/plot/rows.dat --plot ${_h}/plot)
