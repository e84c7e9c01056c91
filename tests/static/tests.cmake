perideal_add_test_program(static_tests ${CMAKE_CURRENT_LIST_DIR}/static_tests.cc)

foreach(_t matrix patch manufactured equilibrium step3_1d)
  perideal_add_test(NAME static.${_t} COMMAND $<TARGET_FILE:static_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME static.matrix.np2 NPROCS 2
  COMMAND $<TARGET_FILE:static_tests> matrix LABELS "unit;mpi")
perideal_add_test(NAME static.rank.np2 NPROCS 2
  COMMAND $<TARGET_FILE:static_tests> rank LABELS mpi)

# Problem = static mechanics through the driver: LPS + CG/AMG on 2 ranks and
# the linearized bond-based model + direct solver on 1 rank; the summary's
# reaction force must balance the body force (global equilibrium).
set(_perideal $<TARGET_FILE:perideal-driver>)
foreach(_case static_plate static_plate_bb)
  if(_case STREQUAL "static_plate")
    set(_np 2)
    set(_labels "unit;mpi")
  else()
    set(_np 1)
    set(_labels unit)
  endif()
  set(_wd ${CMAKE_BINARY_DIR}/tests/run/${_case})
  file(MAKE_DIRECTORY ${_wd})
  perideal_add_test(NAME static.driver.${_case}
    COMMAND ${CMAKE_CURRENT_LIST_DIR}/check_summary.sh ${_wd}/output/summary.txt 1e-9
            ${DEAL_II_MPIEXEC} -n ${_np} --oversubscribe ${_perideal}
            ${CMAKE_CURRENT_LIST_DIR}/${_case}.prm
    LABELS ${_labels} WORKING_DIRECTORY ${_wd})
endforeach()
set_tests_properties(static.driver.static_plate PROPERTIES PROCESSORS 2)
perideal_add_test(NAME static.driver.bad_input
  COMMAND ${CMAKE_CURRENT_LIST_DIR}/../driver/expect_failure.sh "Model/LPS/Critical stretch"
          ${_perideal} ${CMAKE_CURRENT_LIST_DIR}/bad_static.prm LABELS unit)
# Trigonometric manufactured solution, delta- and m-refinement (reported
# rates; LPS at m = 6 is a large two-hop matrix).
perideal_add_test(NAME static.trig COMMAND $<TARGET_FILE:static_tests> trig LABELS long)
