perideal_add_test_program(diffusion_tests ${CMAKE_CURRENT_LIST_DIR}/diffusion_tests.cc)

foreach(_t kernel_constants volume_factor family_counts bad_input stability_bound mesh_domain)
  perideal_add_test(NAME diffusion.${_t} COMMAND $<TARGET_FILE:diffusion_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME diffusion.quadratic_operator
  COMMAND $<TARGET_FILE:diffusion_tests> quadratic_operator LABELS "unit;convergence")
perideal_add_test(NAME diffusion.mass_conservation
  COMMAND $<TARGET_FILE:diffusion_tests> mass_conservation LABELS unit)
perideal_add_test(NAME diffusion.mass_conservation.np2 NPROCS 2
  COMMAND $<TARGET_FILE:diffusion_tests> mass_conservation LABELS "unit;mpi")
perideal_add_test(NAME diffusion.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:diffusion_tests> rank_invariance LABELS mpi)
