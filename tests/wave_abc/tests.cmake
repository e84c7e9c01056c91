perideal_add_test_program(wave_abc_tests ${CMAKE_CURRENT_LIST_DIR}/wave_abc_tests.cc
  ${CMAKE_CURRENT_LIST_DIR}/reference_stepping.cc)
# The reference stepping of wave_abc.compact_levels with the library's flags
# (bitwise comparison with PdUnboundedWave::advance()).
if(PERIDEAL_NATIVE)
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/reference_stepping.cc
    PROPERTIES COMPILE_OPTIONS "-march=native;$<$<CONFIG:Release>:-O3>")
else()
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/reference_stepping.cc
    PROPERTIES COMPILE_OPTIONS "$<$<CONFIG:Release>:-O3>")
endif()

foreach(_t dispersion updating_vectors spectral_radius semi_discrete sponge pml abc_skipped shared_vectors compact_levels pd_2d_stable)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS unit)
endforeach()
foreach(_t pd_1d_modes pd_2d fem_2d pd_1d_dispersive pd_2d_notches pd_2d_notches_source)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS convergence)
endforeach()
# E12c at the source's size (150,000 steps) and the EBF part of the
# semi-discrete analysis (two dense 2D eigenproblems); the sponge over 1e6 steps;
# E15 at the source's radii (26, 42; ~270k nodes in all); the stable m = 6
# EBF layer over 1e6 steps.
foreach(_t pd_1d_dispersive_full semi_discrete_ebf sponge_long pml_long pd_2d_notches_full pd_2d_notches_source_full)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:wave_abc_tests> ${_t} LABELS long TIMEOUT 1200)
endforeach()
# E14 at the source's size (R = 26, t = 40 and 50; 80 s CPU).
perideal_add_test(NAME wave_abc.pd_2d_source_size COMMAND $<TARGET_FILE:wave_abc_tests> pd_2d_source_size
  LABELS long TIMEOUT 1200)
# Three layer settings over 1e6 steps each, one with the energy at every step.
perideal_add_test(NAME wave_abc.pd_2d_stable_long COMMAND $<TARGET_FILE:wave_abc_tests> pd_2d_stable_long
  LABELS long TIMEOUT 2400)
perideal_add_test(NAME wave_abc.shared_vectors.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_abc_tests> shared_vectors LABELS mpi)
perideal_add_test(NAME wave_abc.compact_levels.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_abc_tests> compact_levels LABELS mpi)
perideal_add_test(NAME wave_abc.pd_2d_ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wave_abc_tests> pd_2d_ranks LABELS mpi)
# step-7 with a reduced near field (radius 6, t_end = 12).
perideal_add_test(NAME wave_abc.tutorial.step-7 COMMAND $<TARGET_FILE:step-7> ${CMAKE_CURRENT_LIST_DIR}/step-7-ci.prm
  LABELS tutorial)
# 1D waves (PD E12b/E12c and FEM) against the conventional first-order ABC
# (4.75) (doc/design.md, session 18, waves1d).
perideal_add_test_program(waves_1d_tests ${CMAKE_CURRENT_LIST_DIR}/waves_1d_tests.cc)
foreach(_t pd_1d_first_order fem_1d_first_order)
  perideal_add_test(NAME wave_abc.${_t} COMMAND $<TARGET_FILE:waves_1d_tests> ${_t} LABELS convergence)
endforeach()
