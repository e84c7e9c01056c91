perideal_add_test_program(abc_tests ${CMAKE_CURRENT_LIST_DIR}/abc_tests.cc)

foreach(_t dispersion frames_and_guards)
  perideal_add_test(NAME abc.${_t} COMMAND $<TARGET_FILE:abc_tests> ${_t} LABELS unit)
endforeach()
foreach(_t fem_1d fem_2d pd_1d pd_2d pd_fourier pd_layer_study corrosion_2d)
  perideal_add_test(NAME abc.${_t} COMMAND $<TARGET_FILE:abc_tests> ${_t} LABELS convergence)
endforeach()
perideal_add_test(NAME abc.pd_rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:abc_tests> pd_rank_invariance LABELS mpi)
# 1e5 steps (t = 100) of the 1D runs of long_stability: energy non-increasing.
perideal_add_test(NAME abc.stability COMMAND $<TARGET_FILE:abc_tests> stability LABELS convergence)
perideal_add_test(NAME abc.long_stability COMMAND $<TARGET_FILE:abc_tests> long_stability
  LABELS long TIMEOUT 3000)
# step-5 with a reduced near field (-10, 10), reference (-50, 50), t_f = 40.
perideal_add_test(NAME abc.tutorial.step-5 COMMAND $<TARGET_FILE:step-5> ${CMAKE_CURRENT_LIST_DIR}/step-5-ci.prm
  LABELS tutorial)
perideal_add_test(NAME abc.tutorial.step-5.full COMMAND $<TARGET_FILE:step-5> ${CMAKE_SOURCE_DIR}/tutorial/step-5/step-5.prm
  LABELS "tutorial;long" TIMEOUT 7200)
perideal_add_test(NAME abc.pd_3d COMMAND $<TARGET_FILE:abc_tests> pd_3d LABELS convergence)
# 3D lattice-sphere truncation: least-squares fit stopped by the guard, monotone fit stable.
perideal_add_test(NAME abc.sphere_truncation COMMAND $<TARGET_FILE:abc_tests> sphere_truncation LABELS convergence)
# 3D corrosion with the extended run on (-3, 3)^3 (227k nodes): too heavy for CI.
perideal_add_test(NAME abc.corrosion_3d COMMAND $<TARGET_FILE:abc_tests> corrosion_3d
  LABELS "convergence;long" TIMEOUT 3000)
# step-6 reduced: HZG letters x 0.25 in a radius-0.6 near field, reference radius 2, t_f = 0.02.
perideal_add_test(NAME abc.tutorial.step-6 COMMAND $<TARGET_FILE:step-6> ${CMAKE_CURRENT_LIST_DIR}/step-6-ci.prm
  LABELS tutorial)
perideal_add_test(NAME abc.tutorial.step-6.full COMMAND $<TARGET_FILE:step-6> ${CMAKE_SOURCE_DIR}/tutorial/step-6/step-6.prm
  LABELS "tutorial;long" TIMEOUT 7200)
perideal_add_test(NAME abc.tutorial.step-6.sphere COMMAND $<TARGET_FILE:step-6> ${CMAKE_SOURCE_DIR}/tutorial/step-6/step-6-sphere.prm
  LABELS "tutorial;long" TIMEOUT 7200)
