# The tutorials check themselves (exit code): observed orders, agreement of
# schemes, the sources' qualitative findings. CI runs the shipped parameter
# files where they are small, reduced copies otherwise.
set(_t ${CMAKE_SOURCE_DIR}/tutorial)
perideal_add_test(NAME tutorial.step-1 COMMAND $<TARGET_FILE:step-1> ${_t}/step-1/step-1.prm
  LABELS "tutorial;convergence" TIMEOUT 1800)
perideal_add_test(NAME tutorial.step-2 COMMAND $<TARGET_FILE:step-2> ${_t}/step-2/step-2.prm
  LABELS "tutorial" TIMEOUT 1800)
perideal_add_test(NAME tutorial.step-2.np2 NPROCS 2
  COMMAND $<TARGET_FILE:step-2> ${CMAKE_CURRENT_LIST_DIR}/step-2-explicit.prm
  LABELS "tutorial;mpi" TIMEOUT 1800)
perideal_add_test(NAME tutorial.step-1.long COMMAND $<TARGET_FILE:step-1> ${CMAKE_CURRENT_LIST_DIR}/step-1-long.prm
  LABELS "tutorial;convergence;long" TIMEOUT 7200)
# step-4 (Kalthoff-Winkler) at the shipped CI resolution on 2 ranks: crack
# angle, tip speed below c_R, energy balance of the reaction force.
perideal_add_test(NAME tutorial.step-4.np2 NPROCS 2
  COMMAND $<TARGET_FILE:step-4> ${_t}/step-4/step-4.prm
  LABELS "tutorial;mpi" TIMEOUT 600)
