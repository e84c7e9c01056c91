perideal_add_test_program(wave_abc_tests ${CMAKE_CURRENT_LIST_DIR}/wave_abc_tests.cc)

foreach(_t dispersion updating_vectors)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS unit)
endforeach()
foreach(_t pd_1d_modes pd_2d)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS convergence)
endforeach()
perideal_add_test(NAME wave_abc.pd_2d_ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_abc_tests> pd_2d_ranks LABELS mpi)
