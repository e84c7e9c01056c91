# step-3: 1D static PD elasticity, m- and delta-convergence of the standard
# scheme (dissertation Sect. 3.2.5). Runs in a few seconds.
perideal_add_test(NAME tutorial.step-3 COMMAND $<TARGET_FILE:step-3>
  ${CMAKE_SOURCE_DIR}/tutorial/step-3/step-3.prm LABELS "tutorial;convergence")
