# Adaptive hybrid configuration (dissertation Sect. 3.3) for bond-based
# fracture: patch test, Kalthoff-Winkler at CI size against the standard
# scheme, rank invariance, bad input, initial Omega_s vs Table 3.3 (one
# executable).
perideal_add_test_program(hybrid_kw_tests ${CMAKE_CURRENT_LIST_DIR}/hybrid_kw_tests.cc)
foreach(_t patch kw bad_input stretch_budget sweep initial_fraction kw_classes kw_lattice kw_equivalence grouped_test row_test half_stencil lattice_order)
  perideal_add_test(NAME hybrid_kw.${_t} COMMAND $<TARGET_FILE:hybrid_kw_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME hybrid_kw.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> rank_invariance LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.kw_equivalence.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> kw_equivalence LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.grouped_test.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> grouped_test LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.row_test.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> row_test LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.sweep.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> sweep LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.half_stencil.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> half_stencil LABELS "unit;mpi")
perideal_add_test(NAME hybrid_kw.lattice_order.np2 NPROCS 2
  COMMAND $<TARGET_FILE:hybrid_kw_tests> lattice_order LABELS "unit;mpi")
