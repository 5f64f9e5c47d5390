# CLI tests of LAS input (issue 27, docs/mapping.md "Point clouds"): the world survey of
# map_cli.cmake (fixture map_build_survey) converted to LAS by tests/apps/pcd_to_las.py, a writer
# independent of rowloc's, then read by `rowloc cloud info` and `rowloc map build`.
set(_las_out ${CMAKE_CURRENT_BINARY_DIR}/las)
set(_las_survey ${CMAKE_CURRENT_BINARY_DIR}/map-build/gappy/survey.pcd)
set(_pcd_to_las ${CMAKE_CURRENT_SOURCE_DIR}/apps/pcd_to_las.py)
file(MAKE_DIRECTORY ${_las_out})
# LAS 1.4 point format 6 at UTM magnitudes (eastings ~5e5 m, northings ~5e6 m, 1 mm scale); LAS 1.2
# point format 1 with 3 extra bytes per record in the world's local ENU metres; and a file whose
# point format byte has LASzip's bit 7 set.
rowloc_command_test(apps.las_convert_world_survey ON "LAS 1.4 format 6"
                    python3 ${_pcd_to_las} ${_las_survey} ${_las_out}/gappy-utm.las --shift 500000 5000000 0)
rowloc_command_test(apps.las_convert_world_survey_local ON "LAS 1.2 format 1"
                    python3 ${_pcd_to_las} ${_las_survey} ${_las_out}/gappy-local.las --version 1.2 --format 1
                    --extra-bytes 3)
rowloc_command_test(apps.las_convert_world_survey_laszip_bit ON "LAS 1.4 format 6"
                    python3 ${_pcd_to_las} ${_las_survey} ${_las_out}/gappy-laszip-bit.las --laszip-bit)
set_tests_properties(apps.las_convert_world_survey apps.las_convert_world_survey_local
                     apps.las_convert_world_survey_laszip_bit PROPERTIES
                     FIXTURES_REQUIRED map_build_survey FIXTURES_SETUP las_survey)

# The extent keeps the millimetres of the shifted coordinates (float would round northings to 0.5 m).
rowloc_cli_test(las_cloud_info_utm ON
                "gappy-utm\\.las: 317852 points, x \\[499999\\.554, 500050\\.376\\] y \\[4999979\\.454, 5000010\\.312\\]"
                cloud info ${_las_out}/gappy-utm.las)
rowloc_cli_test(las_map_build_utm ON "gappy-utm\\.las: 5 rows \\(10 parts"
                map build ${_las_out}/gappy-utm.las -o ${_las_out}/built-utm --crs EPSG:32632)
# Local ENU LAS: the same map as from the PCD, within the issue's 2 cm p95 of the true map.
rowloc_cli_test(las_map_build_local ON "gappy-local\\.las: 5 rows \\(10 parts"
                map build ${_las_out}/gappy-local.las -o ${_las_out}/built-local --origin 45.0703 7.6869 240.0)
rowloc_cli_test(las_map_build_local_matches_the_truth ON "PASS: p95"
                map compare ${_las_out}/built-local/row-map.geojson ${CMAKE_CURRENT_BINARY_DIR}/map-build/gappy/row-map.geojson
                --require-p95 0.02)
rowloc_cli_test(las_refuses_laszip_bit OFF
                "cloud info: point cloud '.*gappy-laszip-bit\\.las': LAZ \\(compressed LAS\\) is not read: convert it with `laszip -i .*gappy-laszip-bit\\.las -o .*gappy-laszip-bit-decompressed\\.las` or `pdal translate "
                cloud info ${_las_out}/gappy-laszip-bit.las)
set_tests_properties(apps.las_cloud_info_utm apps.las_map_build_utm apps.las_map_build_local apps.las_refuses_laszip_bit
                     PROPERTIES FIXTURES_REQUIRED "map_build_survey;las_survey")
set_tests_properties(apps.las_map_build_local PROPERTIES FIXTURES_SETUP las_map_local)
set_tests_properties(apps.las_map_build_local_matches_the_truth PROPERTIES
                     FIXTURES_REQUIRED "map_build_survey;las_survey;las_map_local")
# .laz is refused by its name, with the conversion, before the file is read.
rowloc_cli_test(las_refuses_laz_extension OFF
                "map build: point cloud '.*survey\\.laz': LAZ \\(compressed LAS\\) is not read: convert it with `laszip -i .*survey\\.laz -o .*survey\\.las`"
                map build ${PROJECT_SOURCE_DIR}/tests/data/mapping/survey.laz -o ${_las_out}/x --origin 45.0703 7.6869 240.0)
rowloc_cli_test(las_rejects_missing_file OFF "nonexistent\\.las" cloud info nonexistent.las)
