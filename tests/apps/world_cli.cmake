# CLI tests of 'rowloc world': the outputs of the shipped worlds (the OctoMap is checked against the
# exact world by the command itself: "OctoMap check passed"), that the mapping side reads them back,
# determinism, and clear errors for bad input.
set(_worlds ${PROJECT_SOURCE_DIR}/config/worlds)
set(_world_out ${CMAKE_CURRENT_BINARY_DIR}/world-cli)

rowloc_cli_test(world_writes_the_vineyard_002_outputs ON
                "row-map.geojson: 6 parts.*survey.pcd: [0-9]+ points.*canopy.bt: [0-9]+ occupied voxels.*OctoMap check passed: 144/144 canopy probes occupied, 48/48 lane probes free"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/vineyard-002)
set_tests_properties(apps.world_writes_the_vineyard_002_outputs PROPERTIES FIXTURES_SETUP world_vineyard_002)

# The files open with the map and cloud readers.
rowloc_cli_test(world_row_map_reads_back ON "rows: 6, segments: " map info ${_world_out}/vineyard-002/row-map.geojson)
rowloc_cli_test(world_survey_reads_back ON "survey.pcd: [0-9]+ points, x \\[-0.0[0-9]+, 50.0[0-9]+\\]"
                cloud info ${_world_out}/vineyard-002/survey.pcd)
set_tests_properties(apps.world_row_map_reads_back apps.world_survey_reads_back
                     PROPERTIES FIXTURES_REQUIRED world_vineyard_002)

# Same world, same seed: the same survey bytes.
rowloc_cli_reproducible_test(world_survey_is_reproducible
                             ${_world_out}/vineyard-002/survey.pcd ${_world_out}/vineyard-002-again/survey.pcd
                             world ${_worlds}/vineyard-002.json -o ${_world_out}/vineyard-002-again --no-octomap)
set_tests_properties(apps.world_survey_is_reproducible PROPERTIES FIXTURES_REQUIRED world_vineyard_002)

# Curved rows, gaps, sloped undulating ground, terrain points and dropout; a coarser OctoMap.
rowloc_cli_test(world_curved_with_terrain ON "OctoMap check passed: 120/120 canopy probes occupied"
                world ${_worlds}/curved.json -o ${_world_out}/curved --survey-terrain --survey-dropout 0.2
                --survey-spacing 0.1 --octomap-resolution 0.1 --seed 11)
rowloc_cli_test(world_row_map_only ON "row-map.geojson: 6 parts at 1.5 m"
                world ${_worlds}/vineyard-002-rough.json -o ${_world_out}/rough --no-survey --no-octomap
                --slice-height 1.5)

# Errors: clear message, non-zero exit.
rowloc_cli_test(world_rejects_missing_file OFF "nonexistent-world.json"
                world nonexistent-world.json -o ${_world_out}/missing)
rowloc_cli_test(world_requires_output OFF "--output is required" world ${_worlds}/vineyard-002.json)
rowloc_cli_test(world_rejects_bad_spacing OFF "--survey-spacing"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --survey-spacing 0)
rowloc_cli_test(world_rejects_bad_noise OFF "--survey-noise"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --survey-noise -0.1)
rowloc_cli_test(world_rejects_bad_resolution OFF "--octomap-resolution"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --octomap-resolution 0)
rowloc_cli_test(world_rejects_bad_step OFF "--step"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --step 0)
rowloc_cli_test(world_rejects_non_numeric_seed OFF "--seed"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --seed many)
rowloc_cli_test(world_rejects_slice_above_the_canopy OFF "no canopy at height"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --slice-height 5)
rowloc_cli_test(world_rejects_too_many_points OFF "--survey-spacing 0.001 m.*limit"
                world ${_worlds}/vineyard-002.json -o ${_world_out}/bad --survey-spacing 0.001 --no-octomap)
# The output directory cannot be created where a file is.
rowloc_cli_test(world_rejects_output_over_a_file OFF "cannot create output directory"
                world ${_worlds}/vineyard-002.json -o ${_worlds}/vineyard-002.json/out)
