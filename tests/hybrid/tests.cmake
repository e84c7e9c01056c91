# Hybrid fixed configuration (dissertation Sect. 3.3) for PD diffusion:
# standard scheme near the boundary, WLS-2 elsewhere (one executable).
perideal_add_test_program(hybrid_tests ${CMAKE_CURRENT_LIST_DIR}/hybrid_tests.cc)
foreach(_t manufactured corrosion bad_input rank_invariance layer_rows_skipped)
  perideal_add_test(NAME hybrid.${_t} COMMAND $<TARGET_FILE:hybrid_tests> ${_t} LABELS unit)
endforeach()
# Run time of standard vs hybrid at dx = 1/160 (printed, not asserted).
perideal_add_test(NAME hybrid.speedup COMMAND $<TARGET_FILE:hybrid_tests> speedup LABELS long)
perideal_add_test(NAME hybrid.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_tests> rank_invariance LABELS "unit;mpi")
