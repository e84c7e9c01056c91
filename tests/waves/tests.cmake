perideal_add_test_program(wave_tests ${CMAKE_CURRENT_LIST_DIR}/wave_tests.cc)

foreach(_t dispersion_relation standing_wave energy time_step_bound)
  perideal_add_test(NAME waves.${_t} COMMAND $<TARGET_FILE:wave_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME waves.standing_wave.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_tests> standing_wave LABELS "unit;mpi")
perideal_add_test(NAME waves.energy.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_tests> energy LABELS "unit;mpi")
perideal_add_test(NAME waves.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_tests> rank_invariance LABELS mpi)
