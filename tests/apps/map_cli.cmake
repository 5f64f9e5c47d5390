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
