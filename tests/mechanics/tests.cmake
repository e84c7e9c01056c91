perideal_add_test_program(mechanics_tests ${CMAKE_CURRENT_LIST_DIR}/mechanics_tests.cc)

foreach(_t constants patch_test rigid_motion bad_input momentum fracture force_kernel half_list lattice_sweep box_state)
  perideal_add_test(NAME mechanics.${_t} COMMAND $<TARGET_FILE:mechanics_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME mechanics.momentum.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> momentum LABELS "unit;mpi")
perideal_add_test(NAME mechanics.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> rank_invariance LABELS mpi)
perideal_add_test(NAME mechanics.force_kernel.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> force_kernel LABELS "unit;mpi")
perideal_add_test(NAME mechanics.half_list.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> half_list LABELS "unit;mpi")
perideal_add_test(NAME mechanics.lattice_sweep.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> lattice_sweep LABELS "unit;mpi")
perideal_add_test(NAME mechanics.box_state.np2 NPROCS 2
  COMMAND $<TARGET_FILE:mechanics_tests> box_state LABELS "unit;mpi")
