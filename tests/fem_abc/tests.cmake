perideal_add_test_program(fem_abc_tests ${CMAKE_CURRENT_LIST_DIR}/fem_abc_tests.cc)
foreach(_t constant_state spectral_radius bad_input backward_euler_guard half_derivative half_derivative_soe diffusion_parameters)
  perideal_add_test(NAME fem_abc.${_t} COMMAND $<TARGET_FILE:fem_abc_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME fem_abc.e13 COMMAND $<TARGET_FILE:fem_abc_tests> e13 LABELS convergence)
# E13 with curved modes (Curvature radius = 64, session 12).
perideal_add_test(NAME fem_abc.e13_curved COMMAND $<TARGET_FILE:fem_abc_tests> e13_curved LABELS convergence)
# Implicit Newmark (lumped, consistent mass): one-step spectral radius with the EBF constraints.
perideal_add_test(NAME fem_abc.newmark_spectral_radius COMMAND $<TARGET_FILE:fem_abc_tests> newmark_spectral_radius LABELS unit)
# E13 with Newmark + consistent mass (80 s: two KLU-factorized systems, 1600 steps).
perideal_add_test(NAME fem_abc.newmark_e13 COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13 LABELS "convergence;long" TIMEOUT 1200)
# Long-run stability of FEM waves with the EBF ABC (Newmark, consistent mass):
# 2e4 steps in CI, 1e6 steps (issue 4) in the long test.
perideal_add_test(NAME fem_abc.newmark_energy_decay COMMAND $<TARGET_FILE:fem_abc_tests> newmark_energy_decay_short LABELS unit)
perideal_add_test(NAME fem_abc.newmark_energy_decay_long COMMAND $<TARGET_FILE:fem_abc_tests> newmark_energy_decay_long LABELS long TIMEOUT 3000)
# Velocity Verlet + lumped mass + EBF with the tangential viscous layer
# (session 13): one-step radius <= 1, energy decay (CI) and 1e6 steps (long).
perideal_add_test(NAME fem_abc.verlet_layer_spectral_radius COMMAND $<TARGET_FILE:fem_abc_tests> verlet_layer_spectral_radius LABELS unit)
perideal_add_test(NAME fem_abc.verlet_energy_decay COMMAND $<TARGET_FILE:fem_abc_tests> verlet_energy_decay_short LABELS unit)
perideal_add_test(NAME fem_abc.verlet_energy_decay_long COMMAND $<TARGET_FILE:fem_abc_tests> verlet_energy_decay_long LABELS long TIMEOUT 3000)
perideal_add_test(NAME fem_abc.e13_verlet_layer COMMAND $<TARGET_FILE:fem_abc_tests> e13_verlet_layer LABELS convergence)
# Session 14: curved modes (rho 64) with Newmark + consistent mass, the
# long-run-stable route: radius and energy decay (unit), E13 ratios (~40 s).
perideal_add_test(NAME fem_abc.newmark_curved_stability COMMAND $<TARGET_FILE:fem_abc_tests> newmark_curved_stability LABELS unit)
perideal_add_test(NAME fem_abc.newmark_e13_curved COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_curved LABELS "convergence;long" TIMEOUT 1200)
# Session 15: the same with clouds of radius 2 and the Tikhonov pseudo-inverse.
perideal_add_test(NAME fem_abc.newmark_tikhonov_stability COMMAND $<TARGET_FILE:fem_abc_tests> newmark_tikhonov_stability LABELS unit)
perideal_add_test(NAME fem_abc.newmark_tikhonov_long COMMAND $<TARGET_FILE:fem_abc_tests> newmark_tikhonov_long LABELS long TIMEOUT 3000)
perideal_add_test(NAME fem_abc.newmark_e13_tikhonov COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_tikhonov LABELS "convergence;long" TIMEOUT 1200)
# Session 17: the wake curvature radius for the k = 0 modes (radius and
# energy decay: unit; E13 ratios: 22-40 s, in CI as the option's accuracy test).
perideal_add_test(NAME fem_abc.newmark_wake_stability COMMAND $<TARGET_FILE:fem_abc_tests> newmark_wake_stability LABELS unit)
perideal_add_test(NAME fem_abc.newmark_e13_wake COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_wake LABELS convergence TIMEOUT 1200)
# E13 at the source's size with the source's mode set (Newmark + consistent mass).
perideal_add_test(NAME fem_abc.newmark_e13_source_size COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_source_size LABELS convergence TIMEOUT 1200)
# FE_Q(2) + EBF with Newmark + consistent mass: one-step radius and energy decay.
perideal_add_test(NAME fem_abc.newmark_q2_stability COMMAND $<TARGET_FILE:fem_abc_tests> newmark_q2_stability LABELS unit)
# Session 18: the per-node wake radius 40 cos(theta)^3 (radius and energy
# decay: unit; E13 ratios, the issue's 10x in the field: ~12-25 s, in CI).
perideal_add_test(NAME fem_abc.newmark_wake_angle_stability COMMAND $<TARGET_FILE:fem_abc_tests> newmark_wake_angle_stability LABELS unit)
perideal_add_test(NAME fem_abc.newmark_e13_wake_angle COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_wake_angle LABELS convergence TIMEOUT 1200)
# The same with FE_Q(2) (about 4 min CPU).
perideal_add_test(NAME fem_abc.newmark_e13_source_size_q2 COMMAND $<TARGET_FILE:fem_abc_tests> newmark_e13_source_size_q2 LABELS "convergence;long" TIMEOUT 2400)
