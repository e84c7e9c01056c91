perideal_add_test_program(wave_abc_tests ${CMAKE_CURRENT_LIST_DIR}/wave_abc_tests.cc)

foreach(_t dispersion updating_vectors spectral_radius)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS unit)
endforeach()
foreach(_t pd_1d_modes pd_2d fem_2d)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS convergence)
endforeach()
perideal_add_test(NAME wave_abc.pd_2d_ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_abc_tests> pd_2d_ranks LABELS mpi)
# step-7 with a reduced near field (radius 6, t_end = 12).
perideal_add_test(NAME wave_abc.tutorial.step-7 COMMAND $<TARGET_FILE:step-7> ${CMAKE_CURRENT_LIST_DIR}/step-7-ci.prm
  LABELS tutorial)
