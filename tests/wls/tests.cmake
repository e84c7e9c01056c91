# WLS collocation quadrature (dissertation Sect. 3.2): unit tests in one
# executable, and tutorial/step-9 (E1: 1D static elasticity, E2: 2D transient
# diffusion) with a reduced parameter file in CI and the full one as 'long'.
perideal_add_test_program(wls_tests ${CMAKE_CURRENT_LIST_DIR}/wls_tests.cc)
foreach(_t operator_rows polynomial_reproduction bond_based_reproduction bad_input)
  perideal_add_test(NAME wls.${_t} COMMAND $<TARGET_FILE:wls_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME wls.rank_invariance COMMAND $<TARGET_FILE:wls_tests> rank_invariance
  LABELS unit)
perideal_add_test(NAME wls.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:wls_tests> rank_invariance LABELS "unit;mpi")
if(TARGET step-9)
  perideal_add_test(NAME wls.step-9 COMMAND $<TARGET_FILE:step-9>
    ${CMAKE_CURRENT_LIST_DIR}/step-9-ci.prm LABELS "tutorial;convergence" TIMEOUT 600)
  perideal_add_test(NAME wls.step-9.long COMMAND $<TARGET_FILE:step-9>
    ${CMAKE_SOURCE_DIR}/tutorial/step-9/step-9.prm LABELS "tutorial;convergence;long"
    TIMEOUT 7200)
endif()

# WLS for the linearized LPS model, the PD scalar wave equation and backward
# Euler diffusion (issue 5): one executable.
perideal_add_test_program(wls_ext_tests ${CMAKE_CURRENT_LIST_DIR}/wls_ext_tests.cc)
foreach(_t lps_rows lps_polynomial wave_dispersion wave_energy be_diffusion)
  perideal_add_test(NAME wls.ext.${_t} COMMAND $<TARGET_FILE:wls_ext_tests> ${_t} LABELS unit)
endforeach()
# 1 vs 2 ranks: each case compares with an in-process serial copy or with
# rank-independent exact values.
foreach(_t lps_polynomial wave_energy be_diffusion)
  perideal_add_test(NAME wls.ext.${_t}.np2 NPROCS 2
    COMMAND $<TARGET_FILE:wls_ext_tests> ${_t} LABELS "unit;mpi")
endforeach()
perideal_add_test(NAME wls.ext.lps_m_convergence COMMAND $<TARGET_FILE:wls_ext_tests>
  lps_m_convergence LABELS "convergence;long" TIMEOUT 1800)
