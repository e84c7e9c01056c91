# Stability, analytical nonlocal solutions and moving interfaces of PD
# diffusion (paper 003): one executable, sub-tests by name.
perideal_add_test_program(stability_tests ${CMAKE_CURRENT_LIST_DIR}/stability_tests.cc)

foreach(_t bounds_closed_form eigenvalue_bound divergence library_bound analytical snm_linear_field
    moving_interface)
  perideal_add_test(NAME stability.${_t} COMMAND $<TARGET_FILE:stability_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME stability.convergence
  COMMAND $<TARGET_FILE:stability_tests> convergence LABELS convergence)
