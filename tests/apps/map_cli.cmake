# CLI tests of 'rowloc map edit' (the map errors of the map-aided robustness runs,
# docs/map-aided-update.md): a shift moves every vertex, a dropped row is gone, and clear errors.
set(_map_out ${CMAKE_CURRENT_BINARY_DIR}/map-edit)
set(_two_rows ${PROJECT_SOURCE_DIR}/tests/data/maps/valid_two_rows.geojson)
file(MAKE_DIRECTORY ${_map_out})
rowloc_cli_test(map_edit_shifts_and_drops ON "wrote 1 rows"
                map edit ${_two_rows} -o ${_map_out}/edited.geojson --shift 0.05 -0.05 --drop-row b)
rowloc_cli_test(map_edit_result_reads_back ON "rows: 1, segments: "
                map info ${_map_out}/edited.geojson)
set_tests_properties(apps.map_edit_shifts_and_drops PROPERTIES FIXTURES_SETUP map_edited)
set_tests_properties(apps.map_edit_result_reads_back PROPERTIES FIXTURES_REQUIRED map_edited)
rowloc_cli_test(map_edit_rejects_unknown_row OFF "no row 'row-9' to drop"
                map edit ${_two_rows} -o ${_map_out}/x.geojson --drop-row row-9)
rowloc_cli_test(map_edit_rejects_dropping_every_row OFF "every row dropped"
                map edit ${_two_rows} -o ${_map_out}/x.geojson --drop-row a --drop-row b)
rowloc_cli_test(map_edit_rejects_bad_map OFF "nan_coordinate.geojson"
                map edit ${PROJECT_SOURCE_DIR}/tests/data/maps/nan_coordinate.geojson -o ${_map_out}/x.geojson)

# CLI tests of 'rowloc map build' (issue 27, docs/mapping.md): a world's survey -> a row map that
# 'rowloc map info' reads and that matches the true map; "no rows" is a result; clear errors.
set(_build_out ${CMAKE_CURRENT_BINARY_DIR}/map-build)
set(_mapping_data ${PROJECT_SOURCE_DIR}/tests/data/mapping)
file(MAKE_DIRECTORY ${_build_out})
rowloc_cli_test(map_build_world_survey ON "gappy.json"
                world ${PROJECT_SOURCE_DIR}/config/worlds/gappy.json -o ${_build_out}/gappy --survey-terrain
                --step 0.01 --no-octomap)
rowloc_cli_test(map_build_builds_the_rows ON "5 rows \\(10 parts.*meshes: .*meshes\\.ply \\([0-9]+ triangles\\)"
                map build ${_build_out}/gappy/survey.pcd -o ${_build_out}/gappy/built --origin 45.0703 7.6869 240.0
                --config ${PROJECT_SOURCE_DIR}/config/mapping/default.json)
rowloc_cli_test(map_build_result_reads_back ON "rows: 10, segments: " map info ${_build_out}/gappy/built/row-map.geojson)
rowloc_cli_test(map_build_matches_the_truth ON "PASS: p95"
                map compare ${_build_out}/gappy/built/row-map.geojson ${_build_out}/gappy/row-map.geojson
                --require-p95 0.02)
set_tests_properties(apps.map_build_world_survey PROPERTIES FIXTURES_SETUP map_build_survey)
set_tests_properties(apps.map_build_builds_the_rows PROPERTIES FIXTURES_REQUIRED map_build_survey
                     FIXTURES_SETUP map_build_map)
set_tests_properties(apps.map_build_result_reads_back apps.map_build_matches_the_truth
                     PROPERTIES FIXTURES_REQUIRED "map_build_survey;map_build_map")
rowloc_cli_test(map_build_no_rows_is_a_result ON "no rows found: "
                map build ${_build_out}/gappy/survey.pcd -o ${_build_out}/no-rows --origin 45.0703 7.6869 240.0
                --config ${_mapping_data}/band-above-canopy.json)
set_tests_properties(apps.map_build_no_rows_is_a_result PROPERTIES FIXTURES_REQUIRED map_build_survey)
rowloc_cli_test(map_build_writes_the_canopy_octomap ON "octomap: .*canopy\\.bt"
                map build ${_build_out}/gappy/survey.pcd -o ${_build_out}/octomap --origin 45.0703 7.6869 240.0
                --octomap 0.05)
set_tests_properties(apps.map_build_writes_the_canopy_octomap PROPERTIES FIXTURES_REQUIRED map_build_survey)
rowloc_cli_test(map_build_rejects_missing_survey OFF "map build: .*nonexistent\\.pcd"
                map build nonexistent.pcd -o ${_build_out}/x --origin 45.0703 7.6869 240.0)
rowloc_cli_test(map_build_rejects_misspelt_config_key OFF "misspelt-key\\.json: rows\\.max_gap: unknown key"
                map build nonexistent.pcd -o ${_build_out}/x --origin 45.0703 7.6869 240.0
                --config ${_mapping_data}/misspelt-key.json)
rowloc_cli_test(map_build_requires_a_georeference OFF "give --origin LAT LON ALT"
                map build nonexistent.pcd -o ${_build_out}/x)
rowloc_cli_test(map_build_rejects_bad_crs OFF "--crs 'EPSG:4326'" map build nonexistent.pcd -o ${_build_out}/x
                --crs EPSG:4326)
rowloc_cli_test(map_build_rejects_empty_cloud OFF "empty\\.pcd" map build ${_mapping_data}/empty.pcd
                -o ${_build_out}/x --origin 45.0703 7.6869 240.0)
# A world's survey (rowloc world ... ARGN) -> rowloc map build (output matching parts_regex) ->
# rowloc map compare --require-p95 0.02 (every true part found, none invented): three tests chained
# by fixtures, named map_build_<name>_survey, _map and _meets_the_target.
function(rowloc_map_build_target_test name world parts_regex)
  set(_dir ${_build_out}/${name})
  rowloc_cli_test(map_build_${name}_survey ON "${world}\\.json"
                  world ${PROJECT_SOURCE_DIR}/config/worlds/${world}.json -o ${_dir} --survey-terrain
                  --step 0.01 --no-octomap ${ARGN})
  rowloc_cli_test(map_build_${name}_map ON "${parts_regex}"
                  map build ${_dir}/survey.pcd -o ${_dir}/built --origin 45.0703 7.6869 240.0)
  rowloc_cli_test(map_build_${name}_meets_the_target ON "PASS: p95"
                  map compare ${_dir}/built/row-map.geojson ${_dir}/row-map.geojson --require-p95 0.02)
  set_tests_properties(apps.map_build_${name}_survey PROPERTIES FIXTURES_SETUP map_build_${name}_survey)
  set_tests_properties(apps.map_build_${name}_map PROPERTIES FIXTURES_REQUIRED map_build_${name}_survey
                       FIXTURES_SETUP map_build_${name}_map)
  set_tests_properties(apps.map_build_${name}_meets_the_target PROPERTIES
                       FIXTURES_REQUIRED "map_build_${name}_survey;map_build_${name}_map")
endfunction()
# The hardest shipped world (S-curve, gaps, slopes, undulation, 1.5 cm roughness) meets the issue's
# target: p95 <= 2 cm, every true part found, none invented (scripts/map-quality runs all worlds).
rowloc_map_build_target_test(curved_world curved "5 rows \\(8 parts")
# Progress bars on request (on a terminal by default), one per stage; a bad --progress is refused.
rowloc_cli_test(map_build_draws_progress_bars ON "clean +\\[#+\\] [0-9]+/[0-9]+.*terrain +\\[#+\\] [0-9]+/[0-9]+"
                map build ${_build_out}/gappy/survey.pcd -o ${_build_out}/progress --origin 45.0703 7.6869 240.0
                --progress always)
set_tests_properties(apps.map_build_draws_progress_bars PROPERTIES FIXTURES_REQUIRED map_build_survey)
rowloc_cli_test(map_build_rejects_bad_progress OFF "--progress"
                map build nonexistent.pcd -o ${_build_out}/x --origin 45.0703 7.6869 240.0 --progress sometimes)
# Scan defects (rowloc world --survey-*): 1 % outliers (below the ground too) and 30 % of the points
# dropped still give every row within 2 cm; a scan from one side of every row gives every row
# within 2 cm too, each part reported as seen from one side (its hidden face from the canopy top);
# with that route off (a config overlay), the parts are reported as single faces, not mapped.
rowloc_map_build_target_test(defects gappy "5 rows \\(10 parts" --survey-outliers 0.01 --survey-dropout 0.3)
rowloc_map_build_target_test(one_sided gappy "5 rows \\(10 parts.*10 parts seen from one side only" --survey-one-sided)
rowloc_cli_test(map_build_one_sided_off_is_reported ON "[0-9]+ parts narrower than outline.min_width_m.*single canopy faces"
                map build ${_build_out}/one_sided/survey.pcd -o ${_build_out}/one_sided/off
                --origin 45.0703 7.6869 240.0 --config ${_mapping_data}/one-sided-off.json)
set_tests_properties(apps.map_build_one_sided_off_is_reported PROPERTIES FIXTURES_REQUIRED map_build_one_sided_survey)
rowloc_cli_test(world_rejects_too_many_outliers OFF "--survey-outliers"
                world ${PROJECT_SOURCE_DIR}/config/worlds/gappy.json -o ${_build_out}/x --survey-outliers 0.6)
