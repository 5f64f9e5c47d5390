# Tests of the Python scripts under scripts/ that drive the rowloc command (`rowloc` built here).

# Runs `scripts/SCRIPT ARGN --rowloc <the built rowloc>` (rowloc_command_test, tests/CMakeLists.txt).
function(rowloc_script_test name expect_success regex script)
  rowloc_command_test(scripts.${name} ${expect_success} "${regex}" ${PROJECT_SOURCE_DIR}/scripts/${script} ${ARGN}
                      --rowloc $<TARGET_FILE:rowloc>)
endfunction()

set(_swerve --vehicle config/vehicles/agrimaro-swerve.json)
# One line per seed; a scenario that keeps its fixes has no final error after a loss.
rowloc_script_test(seed_sweep_tiles ON
  "\\| 1 \\| - \\| [0-9.]+ \\(2\\.62-3\\.40\\) \\| [0-9.]+ wheels .*\\| 2 \\| - \\| .*over 2 seeds.*never loses its absolute fixes"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter config/filters/default.json --seeds 1-2)
# A scenario that loses them: the final error, counted against the threshold.
rowloc_script_test(seed_sweep_turns ON
  "\\| 3 \\| 0\\.[0-9]+ \\| .* wheel_angles .*final error: median 0\\.[0-9]+ m, max 0\\.[0-9]+ m, [01] of 1 seeds <= 0\\.15 m"
  seed-sweep config/scenarios/slip-odometry-turns.json --vehicle config/vehicles/differential.json
  --filter config/filters/wheel-angles.json --seeds 3)
rowloc_script_test(seed_sweep_rejects_empty_range OFF "seeds 3-1: the range is empty"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter config/filters/default.json --seeds 3-1)
rowloc_script_test(seed_sweep_rejects_missing_scenario OFF "no such file: config/scenarios/absent.json"
  seed-sweep config/scenarios/absent.json ${_swerve} --filter config/filters/default.json --seeds 1)
# A run that fails names its command and shows rowloc's error.
rowloc_script_test(seed_sweep_reports_a_failed_run OFF "seed-sweep: .*rowloc replay .*failed \\(2\\):.*bad-gate\\.json: .*gate_probability"
  seed-sweep config/scenarios/agrimaro-tiles.json ${_swerve} --filter tests/data/filters/bad-gate.json --seeds 1)
