# CLI tests of 'rowloc evaluate' (fixtures in tests/data/evaluate, written by hand; docs/validation.md).
set(_eval_data ${PROJECT_SOURCE_DIR}/tests/data/evaluate)
set(_eval_out ${CMAKE_CURRENT_BINARY_DIR}/evaluate)
rowloc_cli_test(evaluate_fixture_report ON "position, total \\[m\\] +21 .*gnss +14 .*1 +8\\.00 +15\\.00 +yes +8 "
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/plain --no-plots)
rowloc_cli_test(evaluate_fixture_with_map ON "row direction \\(nearest row segment"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/map
                --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson --no-plots)
rowloc_cli_test(evaluate_json_summary ON "\"schema\": \"rowloc-evaluation/1\""
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/json --json --no-plots)
rowloc_cli_test(evaluate_rejects_missing_file OFF "truth .nonexistent-truth.ndjson.: no such file"
                evaluate nonexistent-truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/missing)
rowloc_cli_test(evaluate_names_malformed_line OFF "estimates_malformed.ndjson:4: malformed JSON"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates_malformed.ndjson -o ${_eval_out}/bad)
rowloc_cli_test(evaluate_rejects_estimate_outside_truth OFF
                "estimates_outside_truth.ndjson:37: estimate at time 25 s is outside the truth's span"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates_outside_truth.ndjson -o ${_eval_out}/out)
# --clip-to-truth drops that estimate, says so, and evaluates the rest.
rowloc_cli_test(evaluate_clip_to_truth_drops_and_counts ON
                "position, total.*--clip-to-truth: 1 estimates and 0 updates outside the truth's span \\[0 s, 20 s\\] not evaluated"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates_outside_truth.ndjson --clip-to-truth
                -o ${_eval_out}/clipped --no-plots)
# --settle S leaves out the first S seconds after the first estimate (convergence), and says so.
rowloc_cli_test(evaluate_settle_drops_the_first_seconds ON
                "position, total \\[m\\] +16 .*--settle 5 s: 5 estimates and [0-9]+ updates before t = 5 s not evaluated"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson --settle 5 -o ${_eval_out}/settle --no-plots)
rowloc_cli_test(evaluate_settle_past_the_end_is_an_error OFF "--settle: no estimate left"
                evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson --settle 100 -o ${_eval_out}/settle2 --no-plots)

# Exit status and written files: a small checker script generated here (run_cli.cmake checks
# only success/failure).
set(_eval_check ${CMAKE_CURRENT_BINARY_DIR}/evaluate_check.cmake)
file(WRITE ${_eval_check} [=[
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT status EQUAL EXPECT_STATUS)
  message(FATAL_ERROR "expected exit status ${EXPECT_STATUS}, got ${status}")
endif()
foreach(f IN LISTS EXPECT_FILES)
  if(NOT EXISTS "${f}")
    message(FATAL_ERROR "missing ${f}")
  endif()
  file(SIZE "${f}" size)
  if(size EQUAL 0)
    message(FATAL_ERROR "empty ${f}")
  endif()
endforeach()
]=])
function(_rowloc_evaluate_check name status files)
  add_test(NAME apps.${name}
           COMMAND ${CMAKE_COMMAND} "-DCOMMAND=$<TARGET_FILE:rowloc>;${ARGN}" -DEXPECT_STATUS=${status}
                   "-DEXPECT_FILES=${files}" -P ${_eval_check}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(apps.${name} PROPERTIES LABELS apps)
endfunction()
_rowloc_evaluate_check(evaluate_error_exit_status_is_2 2 ""
                       evaluate nonexistent-truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/status)
set(_eval_plots ${_eval_out}/plots/plots)
set(_eval_files ${_eval_out}/plots/report.txt ${_eval_out}/plots/report.json ${_eval_plots}/plots.gp
                ${_eval_plots}/truth.dat ${_eval_plots}/estimate.dat ${_eval_plots}/errors.dat)
find_program(_eval_gnuplot gnuplot)
if(_eval_gnuplot)  # otherwise the command warns and still succeeds
  list(APPEND _eval_files ${_eval_plots}/trajectory.svg ${_eval_plots}/errors.svg ${_eval_plots}/histograms.svg
                          ${_eval_plots}/consistency.svg)
endif()
_rowloc_evaluate_check(evaluate_writes_report_and_plots 0 "${_eval_files}"
                       evaluate ${_eval_data}/truth.ndjson ${_eval_data}/estimates.ndjson -o ${_eval_out}/plots
                       --map ${PROJECT_SOURCE_DIR}/maps/sample-vineyard.geojson)
