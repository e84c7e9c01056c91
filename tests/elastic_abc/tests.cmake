perideal_add_test_program(elastic_abc_tests ${CMAKE_CURRENT_LIST_DIR}/elastic_abc_tests.cc)

foreach(_t dispersion guards sponge)
  perideal_add_test(NAME elastic_abc.${_t} COMMAND $<TARGET_FILE:elastic_abc_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME elastic_abc.unbounded COMMAND $<TARGET_FILE:elastic_abc_tests> unbounded
  LABELS convergence)
perideal_add_test(NAME elastic_abc.ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:elastic_abc_tests> ranks LABELS mpi)
# The elastic PML (doc/design.md, session 9): E16 CI accuracy, 10,000
# undamped steps, parameter errors (seconds); 1e6 undamped steps (long).
perideal_add_test(NAME elastic_abc.pml COMMAND $<TARGET_FILE:elastic_abc_tests> pml
  LABELS "unit;convergence")
perideal_add_test(NAME elastic_abc.pml_long COMMAND $<TARGET_FILE:elastic_abc_tests> pml_long
  LABELS long TIMEOUT 3000)
perideal_add_test(NAME elastic_abc.pml_spectral_radius COMMAND $<TARGET_FILE:elastic_abc_tests> pml_spectral_radius
  LABELS long TIMEOUT 1200)
perideal_add_test(NAME elastic_abc.unbounded_long COMMAND $<TARGET_FILE:elastic_abc_tests> unbounded_long
  LABELS long TIMEOUT 3000)
# step-8 with a reduced near field (disc radius 12, half-space 40 x 20).
perideal_add_test(NAME elastic_abc.tutorial.step-8 COMMAND $<TARGET_FILE:step-8> ${CMAKE_CURRENT_LIST_DIR}/step-8-ci.prm
  LABELS tutorial)
perideal_add_test(NAME elastic_abc.tutorial.step-8-pml COMMAND $<TARGET_FILE:step-8> ${CMAKE_CURRENT_LIST_DIR}/step-8-ci-pml.prm
  LABELS tutorial)
# Dense one-step map (about 4,000 x 4,000): ~40 s, so long.
perideal_add_test(NAME elastic_abc.spectral_radius COMMAND $<TARGET_FILE:elastic_abc_tests> spectral_radius
  LABELS long TIMEOUT 600)
# The conventional first-order (Lysmer-type) ABC as the EBF baseline
# (issue 4; doc/design.md, session 18): E16 at CI size.
perideal_add_test(NAME elastic_abc.first_order COMMAND $<TARGET_FILE:elastic_abc_tests> first_order
  LABELS "unit;convergence")
# One EBF setting >= 10x closer than the first-order ABC on both E16
# sizes, long-run stable (ElasticAbcLayers::curved_tikhonov; session 19).
perideal_add_test(NAME elastic_abc.curved_tikhonov COMMAND $<TARGET_FILE:elastic_abc_tests> curved_tikhonov
  LABELS convergence)
