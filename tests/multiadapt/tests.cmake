# Two-grid explicit mechanics and the multi-adaptive scheme
# (MultiGrid::MechanicsSolver): patch tests, mass and momentum, a 1D wave
# against the uniform fine grid, the CI-size Kalthoff-Winkler experiment.
perideal_add_test_program(multiadapt_tests ${CMAKE_CURRENT_LIST_DIR}/multiadapt_tests.cc)
foreach(_t patch mass_momentum conservative_coupling wave kw bad_input incremental_switch)
  perideal_add_test(NAME multiadapt.${_t} COMMAND $<TARGET_FILE:multiadapt_tests> ${_t} LABELS unit)
endforeach()
# The same assertions on 2 ranks (the MPI standard: rank-count independent).
foreach(_t kw incremental_switch)
  perideal_add_test(NAME multiadapt.${_t}.np2 NPROCS 2
    COMMAND $<TARGET_FILE:multiadapt_tests> ${_t} LABELS "unit;mpi")
endforeach()
# tutorial/step-11 (multi-adaptive Kalthoff-Winkler) with a reduced parameter file.
perideal_add_test(NAME tutorial.step-11 COMMAND $<TARGET_FILE:step-11>
  ${CMAKE_CURRENT_LIST_DIR}/step-11-ci.prm LABELS "tutorial" TIMEOUT 600)
