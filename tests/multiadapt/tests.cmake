# Two-grid explicit mechanics and the multi-adaptive scheme
# (MultiGrid::MechanicsSolver): patch tests, mass and momentum, a 1D wave
# against the uniform fine grid, the CI-size Kalthoff-Winkler experiment.
perideal_add_test_program(multiadapt_tests ${CMAKE_CURRENT_LIST_DIR}/multiadapt_tests.cc)
foreach(_t patch mass_momentum wave kw bad_input)
  perideal_add_test(NAME multiadapt.${_t} COMMAND $<TARGET_FILE:multiadapt_tests> ${_t} LABELS unit)
endforeach()
