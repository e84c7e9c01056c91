perideal_add_test_program(fnm_tests ${CMAKE_CURRENT_LIST_DIR}/fnm_tests.cc)

# mirror_square mirror_reentrant mirror_crack mirror_circle crack_mesh bad_input
perideal_add_test(NAME fnm.unit COMMAND $<TARGET_FILE:fnm_tests> unit LABELS unit)
foreach(_t square_linear disk_harmonic motz cracked_disk crossing_cracks)
  perideal_add_test(NAME fnm.${_t} COMMAND $<TARGET_FILE:fnm_tests> ${_t} LABELS convergence)
endforeach()
foreach(_t square_convergence motz_convergence cracked_disk_fine crossing_cracks_fine)
  perideal_add_test(NAME fnm.${_t} COMMAND $<TARGET_FILE:fnm_tests> ${_t}
    LABELS "convergence;long" TIMEOUT 3000)
endforeach()
perideal_add_test(NAME fnm.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:fnm_tests> rank_invariance LABELS mpi)
perideal_add_test(NAME tutorial.step-12 COMMAND $<TARGET_FILE:step-12> ${CMAKE_CURRENT_LIST_DIR}/step-12-ci.prm
  LABELS "tutorial;convergence" TIMEOUT 600)
# Transient FNM runs, the Gershgorin time step and domains that change
# (corrosion, fracture) with locally rebuilt mirror nodes.
perideal_add_test(NAME fnm.transient COMMAND $<TARGET_FILE:fnm_tests> transient LABELS "unit;convergence")
perideal_add_test(NAME fnm.transient_ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:fnm_tests> transient_ranks LABELS mpi)
# 3D: mirror nodes on a cube and a ball, steady analytical solutions.
perideal_add_test(NAME fnm.3d COMMAND $<TARGET_FILE:fnm_tests> 3d LABELS "unit;convergence")
perideal_add_test(NAME fnm.3d_fine COMMAND $<TARGET_FILE:fnm_tests> steady_3d_fine
  LABELS "convergence;long" TIMEOUT 3000)
perideal_add_test(NAME fnm.rank_invariance_3d.np2 NPROCS 2
  COMMAND $<TARGET_FILE:fnm_tests> rank_invariance_3d LABELS mpi)
