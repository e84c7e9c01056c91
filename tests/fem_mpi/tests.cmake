perideal_add_test_program(fem_mpi_tests ${CMAKE_CURRENT_LIST_DIR}/fem_mpi_tests.cc)
# 1 vs 2 ranks: parallel::distributed runs equal the serial ones DoF by DoF.
foreach(_t rank_invariance_diffusion rank_invariance_wave)
  perideal_add_test(NAME fem_mpi.${_t}.np2 NPROCS 2 COMMAND $<TARGET_FILE:fem_mpi_tests> ${_t} LABELS mpi)
endforeach()
# Disk near fields: diffusion vs the heat kernel, waves vs an extended disk.
foreach(_t disk_diffusion disk_wave disk_wave_compact disk_wave_cloud_size)
  perideal_add_test(NAME fem_mpi.${_t} COMMAND $<TARGET_FILE:fem_mpi_tests> ${_t} LABELS convergence)
endforeach()
# 3D FEM diffusion with the EBF ABC (octant frame) on a cube and a ball vs the heat kernel.
perideal_add_test(NAME fem_mpi.diffusion_3d_cube_ball COMMAND $<TARGET_FILE:fem_mpi_tests> diffusion_3d_cube_ball LABELS convergence)
# Session 14: the half-derivative ABC's sum-of-exponentials history vs the exact sum (disk, 6000 steps).
perideal_add_test(NAME fem_mpi.half_derivative_history COMMAND $<TARGET_FILE:fem_mpi_tests> half_derivative_history LABELS convergence)
