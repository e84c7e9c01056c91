perideal_add_test_program(lps_tests ${CMAKE_CURRENT_LIST_DIR}/lps_tests.cc)

foreach(_t homogeneous rigid_motion navier energy_gradient)
  perideal_add_test(NAME lps.${_t} COMMAND $<TARGET_FILE:lps_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME lps.homogeneous.np2 NPROCS 2
  COMMAND $<TARGET_FILE:lps_tests> homogeneous LABELS "unit;mpi")
perideal_add_test(NAME lps.rank_invariance.np2 NPROCS 2
  COMMAND $<TARGET_FILE:lps_tests> rank_invariance LABELS mpi)
foreach(_t time_step breaking)
  perideal_add_test(NAME lps.${_t} COMMAND $<TARGET_FILE:lps_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME lps.breaking.np2 NPROCS 2
  COMMAND $<TARGET_FILE:lps_tests> breaking LABELS "unit;mpi")
# LPS in explicit mechanics runs (helper lps).
foreach(_t explicit_patch explicit_momentum)
  perideal_add_test(NAME lps.${_t} COMMAND $<TARGET_FILE:lps_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME lps.explicit_momentum.np2 NPROCS 2
  COMMAND $<TARGET_FILE:lps_tests> explicit_momentum LABELS "unit;mpi")
perideal_add_test(NAME lps.explicit_crack COMMAND $<TARGET_FILE:lps_tests> explicit_crack LABELS unit)
perideal_add_test(NAME lps.explicit_crack.np2 NPROCS 2
  COMMAND $<TARGET_FILE:lps_tests> explicit_crack_ranks LABELS mpi)
perideal_add_test(NAME lps.explicit_resume COMMAND $<TARGET_FILE:lps_tests> explicit_resume LABELS unit)
perideal_add_test(NAME lps.fracture_energy COMMAND $<TARGET_FILE:lps_tests> fracture_energy LABELS unit)
foreach(_t wave reaction_inertia)
  perideal_add_test(NAME lps.${_t} COMMAND $<TARGET_FILE:lps_tests> ${_t} LABELS unit)
endforeach()
# Problem = mechanics, Mechanics/Model = LPS through the driver on 2 ranks:
# straight run vs stop-and-resume (identical node tables), bonds breaking.
set(_wd ${CMAKE_BINARY_DIR}/tests/run/lps_plate)
file(MAKE_DIRECTORY ${_wd})
perideal_add_test(NAME lps.driver.resume.np2
  COMMAND ${CMAKE_CURRENT_LIST_DIR}/run_resume.sh $<TARGET_FILE:perideal-driver>
          ${CMAKE_CURRENT_LIST_DIR}/lps_plate.prm ${DEAL_II_MPIEXEC} -n 2 --oversubscribe
  LABELS "unit;mpi" WORKING_DIRECTORY ${_wd})
set_tests_properties(lps.driver.resume.np2 PROPERTIES PROCESSORS 2)
perideal_add_test(NAME lps.driver.bad_input
  COMMAND ${CMAKE_CURRENT_LIST_DIR}/../driver/expect_failure.sh "Mechanics/Model"
          $<TARGET_FILE:perideal-driver> ${CMAKE_CURRENT_LIST_DIR}/bad_lps_1d.prm LABELS unit)
