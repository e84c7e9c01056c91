# Tests of the perideal driver: parameter printing, error exits, and
# checkpoint/restart (an interrupted and resumed run equals the
# uninterrupted one).
set(_d ${CMAKE_CURRENT_LIST_DIR})
set(_perideal $<TARGET_FILE:perideal-driver>)

perideal_add_test(NAME driver.print_parameters COMMAND ${_perideal} --print-parameters
  LABELS unit)
set_tests_properties(driver.print_parameters PROPERTIES
  PASS_REGULAR_EXPRESSION "Volume constraint layer.*Saturation concentration")

perideal_add_test(NAME driver.bad_time_step
  COMMAND ${_d}/expect_failure.sh "Time stepping/Time step.*stability bound"
          ${_perideal} ${_d}/bad_time_step.prm LABELS unit)
perideal_add_test(NAME driver.missing_file
  COMMAND ${_d}/expect_failure.sh "readable parameter file" ${_perideal} /no/such.prm
  LABELS unit)
perideal_add_test(NAME driver.unknown_entry
  COMMAND ${_d}/expect_failure.sh "Could not read parameter file"
          ${_perideal} ${_d}/unknown_entry.prm LABELS unit)

# Uninterrupted reference, then a run stopped after 27 steps (last
# checkpoint at 20) and resumed on 2 ranks; final node tables must agree.
perideal_add_test(NAME driver.restart.reference COMMAND ${_perideal} ${_d}/restart.prm
  LABELS unit FIXTURES_SETUP restart_ref
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/restart_ref)
perideal_add_test(NAME driver.restart.interrupted
  COMMAND ${_perideal} --stop-after-steps 27 ${_d}/restart.prm
  LABELS unit FIXTURES_SETUP restart_int
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/restart_int)
perideal_add_test(NAME driver.restart.resumed NPROCS 2
  COMMAND ${_perideal} --resume ${_d}/restart.prm
  LABELS "unit;mpi" FIXTURES_SETUP restart_res FIXTURES_REQUIRED restart_int
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/restart_int)
# Restart replays steps 21-27 with the same arithmetic: round-off only.
perideal_add_test(NAME driver.restart.compare
  COMMAND ${_perideal} --compare ${CMAKE_BINARY_DIR}/tests/run/restart_ref/output/nodes.csv
          ${CMAKE_BINARY_DIR}/tests/run/restart_int/output/nodes.csv 1e-12
  LABELS unit FIXTURES_REQUIRED "restart_ref;restart_res")

# An outside project finds the build tree's PeriDEAL package and links it.
perideal_add_test(NAME driver.find_package
  COMMAND ${CMAKE_COMMAND} -DSOURCE=${_d}/outside_project -DBINARY=${CMAKE_BINARY_DIR}/tests/run/find_package/build
          -DPERIDEAL_DIR=${CMAKE_BINARY_DIR} -P ${_d}/outside_project/run.cmake
  LABELS unit)

# Problem = mechanics through the driver on 2 ranks: the plate cracks.
perideal_add_test(NAME driver.mechanics NPROCS 2 COMMAND ${_perideal} ${_d}/crack_plate.prm
  LABELS "unit;mpi" TIMEOUT 300)
set_tests_properties(driver.mechanics PROPERTIES
  PASS_REGULAR_EXPRESSION "Final: t = 300, total energy = [0-9.e-]+, broken bonds = [1-9][0-9]*")

# Checkpoint/restart of a mechanics run with fracture: uninterrupted
# reference on 1 rank, a run stopped after 137 steps (last checkpoint at 100)
# and resumed on 2 ranks; u, v and damage of all nodes must agree.
perideal_add_test(NAME driver.mechanics_restart.reference
  COMMAND ${_perideal} ${_d}/mechanics_restart.prm
  LABELS unit FIXTURES_SETUP mech_restart_ref
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/mech_restart_ref)
perideal_add_test(NAME driver.mechanics_restart.interrupted
  COMMAND ${_perideal} --stop-after-steps 137 ${_d}/mechanics_restart.prm
  LABELS unit FIXTURES_SETUP mech_restart_int
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/mech_restart_int)
perideal_add_test(NAME driver.mechanics_restart.resumed NPROCS 2
  COMMAND ${_perideal} --resume ${_d}/mechanics_restart.prm
  LABELS "unit;mpi" FIXTURES_SETUP mech_restart_res FIXTURES_REQUIRED mech_restart_int
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}/tests/run/mech_restart_int)
# Same arithmetic per bond on any rank count (see mechanics.rank_invariance):
# round-off only.
perideal_add_test(NAME driver.mechanics_restart.compare
  COMMAND ${_perideal} --compare ${CMAKE_BINARY_DIR}/tests/run/mech_restart_ref/output/nodes.csv
          ${CMAKE_BINARY_DIR}/tests/run/mech_restart_int/output/nodes.csv 1e-12
  LABELS unit FIXTURES_REQUIRED "mech_restart_ref;mech_restart_res")
