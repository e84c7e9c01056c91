# Stability, analytical nonlocal solutions and moving interfaces of PD
# diffusion (paper 003): one executable, sub-tests by name.
perideal_add_test_program(stability_tests ${CMAKE_CURRENT_LIST_DIR}/stability_tests.cc)

foreach(_t bounds_closed_form eigenvalue_bound divergence library_bound analytical snm_linear_field
    moving_interface library_phase_rule)
  perideal_add_test(NAME stability.${_t} COMMAND $<TARGET_FILE:stability_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME stability.convergence
  COMMAND $<TARGET_FILE:stability_tests> convergence LABELS convergence)

# tutorial step-13: reduced parameters in CI, the shipped file as long
perideal_add_test(NAME tutorial.step-13 COMMAND $<TARGET_FILE:step-13>
  ${CMAKE_CURRENT_LIST_DIR}/step-13-small.prm LABELS "tutorial;convergence")
perideal_add_test(NAME tutorial.step-13.long COMMAND $<TARGET_FILE:step-13>
  ${CMAKE_SOURCE_DIR}/tutorial/step-13/step-13.prm LABELS "tutorial;convergence;long" TIMEOUT 3600)
perideal_add_test(NAME stability.library_phase_rule.np2 NPROCS 2
  COMMAND $<TARGET_FILE:stability_tests> library_phase_rule LABELS "unit;mpi")
