perideal_add_test_program(multigrid_tests ${CMAKE_CURRENT_LIST_DIR}/multigrid_tests.cc)

foreach(_t node_counts bad_input consistency interface_flux_2d coarse_wls_exactness)
  perideal_add_test(NAME multigrid.${_t} COMMAND $<TARGET_FILE:multigrid_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME multigrid.diffusion_rod
  COMMAND $<TARGET_FILE:multigrid_tests> diffusion_rod LABELS "unit;convergence")
perideal_add_test(NAME multigrid.e5_corrosion_1d
  COMMAND $<TARGET_FILE:multigrid_tests> e5 LABELS "unit;convergence")
perideal_add_test(NAME tutorial.step-10
  COMMAND $<TARGET_FILE:step-10> ${CMAKE_SOURCE_DIR}/tutorial/step-10/step-10.prm
  LABELS tutorial TIMEOUT 600)
# 3D corrosion, hybrid fixed configuration vs standard (Sect. 3.3.2, reduced)
perideal_add_test(NAME multigrid.hybrid_corrosion_3d
  COMMAND $<TARGET_FILE:multigrid_tests> hybrid_corrosion_3d LABELS unit)
# 3D multi-grid corrosion (reduced [100] Example 2): uniform fine vs
# multi-grid vs adaptive hybrid (WLS on the coarse grid)
perideal_add_test(NAME multigrid.corrosion_3d
  COMMAND $<TARGET_FILE:multigrid_tests> corrosion_3d LABELS unit)
perideal_add_test(NAME multigrid.hybrid_corrosion_3d.np2 NPROCS 2
  COMMAND $<TARGET_FILE:multigrid_tests> hybrid_corrosion_3d_ranks LABELS "unit;mpi")
# Phase classification of the corrosion operators vs the per-bond kernel
perideal_add_test(NAME multigrid.phase_classification
  COMMAND $<TARGET_FILE:multigrid_tests> phase_classification LABELS unit)
