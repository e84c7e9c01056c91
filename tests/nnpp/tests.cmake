perideal_add_test_program(nnpp_tests ${CMAKE_CURRENT_LIST_DIR}/nnpp_tests.cc)

foreach(_t k_constants bad_input jacobian)
  perideal_add_test(NAME nnpp.${_t} COMMAND $<TARGET_FILE:nnpp_tests> ${_t} LABELS unit)
endforeach()
foreach(_t local_limit manufactured)
  perideal_add_test(NAME nnpp.${_t} COMMAND $<TARGET_FILE:nnpp_tests> ${_t}
    LABELS "unit;convergence")
endforeach()
perideal_add_test(NAME nnpp.mass_conservation
  COMMAND $<TARGET_FILE:nnpp_tests> mass_conservation LABELS unit)
perideal_add_test(NAME nnpp.mass_conservation.np2 NPROCS 2
  COMMAND $<TARGET_FILE:nnpp_tests> mass_conservation LABELS "unit;mpi")
perideal_add_test(NAME nnpp.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:nnpp_tests> rank_invariance LABELS mpi)
perideal_add_test(NAME nnpp.phase_change
  COMMAND $<TARGET_FILE:nnpp_tests> phase_change LABELS unit)
perideal_add_test(NAME nnpp.phase_change.np2 NPROCS 2
  COMMAND $<TARGET_FILE:nnpp_tests> phase_change LABELS "unit;mpi")
