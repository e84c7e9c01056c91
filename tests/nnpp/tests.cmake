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

# Problem = nnpp through the perideal driver (VTU + CSV + PNG). The amounts
# in the final line are hand counts (see the .prm headers): mass is conserved.
set(_perideal $<TARGET_FILE:perideal-driver>)
perideal_add_test(NAME driver.nnpp.1d COMMAND ${_perideal} ${CMAKE_SOURCE_DIR}/tutorial/step-14/step-14.prm
  LABELS tutorial)
set_tests_properties(driver.nnpp.1d PROPERTIES
  PASS_REGULAR_EXPRESSION "Final: t = 0.25, amounts = 0.65 1.3, solid volume = 0, max [|]phi[|] = 0.[0-9]+")
perideal_add_test(NAME driver.nnpp.2d.np2 NPROCS 2 COMMAND ${_perideal} ${CMAKE_CURRENT_LIST_DIR}/driver_2d.prm
  LABELS "tutorial;mpi")
set_tests_properties(driver.nnpp.2d.np2 PROPERTIES
  PASS_REGULAR_EXPRESSION "Final: t = 0.05, amounts = 0.65 1.3, solid volume = 0.[0-9]+, max [|]phi[|] = 0.[0-9]+")
perideal_add_test(NAME driver.nnpp.3d COMMAND ${_perideal} ${CMAKE_CURRENT_LIST_DIR}/driver_3d.prm
  LABELS tutorial)
set_tests_properties(driver.nnpp.3d PROPERTIES
  PASS_REGULAR_EXPRESSION "Final: t = 0.05, amounts = 0.1625 0.325, solid volume = 0.[0-9]+, max [|]phi[|] = 0.[0-9]+")
perideal_add_test(NAME driver.nnpp.print_parameters COMMAND ${_perideal} --print-parameters LABELS unit)
set_tests_properties(driver.nnpp.print_parameters PROPERTIES
  PASS_REGULAR_EXPRESSION "nnpp.*subsection NNPP.*Valences.*Initial concentrations.*Boundary potential.*End time")
set(_fail ${CMAKE_SOURCE_DIR}/tests/driver/expect_failure.sh)
perideal_add_test(NAME driver.nnpp.bad_initial
  COMMAND ${_fail} "NNPP/Initial concentrations.*one expression per species"
          ${_perideal} ${CMAKE_CURRENT_LIST_DIR}/bad_initial.prm LABELS unit)
perideal_add_test(NAME driver.nnpp.bad_layer
  COMMAND ${_fail} "Discretization/Volume constraint layer.*non-zero"
          ${_perideal} ${CMAKE_CURRENT_LIST_DIR}/bad_layer.prm LABELS unit)
# tutorial/step-14: migration vs z = 0, and the z = 0 run against the PD
# corrosion model (DiffusionSolver) node by node and step by step.
perideal_add_test(NAME tutorial.step-14 COMMAND $<TARGET_FILE:step-14> ${CMAKE_SOURCE_DIR}/tutorial/step-14/step-14.prm
  LABELS "tutorial;unit")
perideal_add_test(NAME tutorial.step-14.np2 NPROCS 2 COMMAND $<TARGET_FILE:step-14> ${CMAKE_SOURCE_DIR}/tutorial/step-14/step-14.prm
  LABELS "tutorial;mpi")
perideal_add_test(NAME driver.nnpp.no_resume
  COMMAND ${_fail} "--resume.*no restart options for Problem = nnpp"
          ${_perideal} --resume ${CMAKE_CURRENT_LIST_DIR}/driver_2d.prm LABELS unit)
