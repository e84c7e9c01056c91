perideal_add_test_program(octree_mg_tests ${CMAKE_CURRENT_LIST_DIR}/octree_mg_tests.cc)

foreach(_t serial_2d serial_3d switching corrosion_2d corrosion_3d coarsening backward_euler
    bad_input)
  perideal_add_test(NAME octree_mg.${_t} COMMAND $<TARGET_FILE:octree_mg_tests> ${_t}
    LABELS unit)
endforeach()
perideal_add_test(NAME octree_mg.ranks.np2 NPROCS 2
  COMMAND $<TARGET_FILE:octree_mg_tests> ranks LABELS "unit;mpi")
# fine -> coarse -> fine and backward Euler on 2 ranks against 1 rank in-process
foreach(_t coarsening backward_euler)
  perideal_add_test(NAME octree_mg.${_t}.np2 NPROCS 2
    COMMAND $<TARGET_FILE:octree_mg_tests> ${_t} LABELS "unit;mpi")
endforeach()
