# Mechanics driver features (helper kw): 3D polygon pre-cracks, damage-field
# measurements, prescribed displacements, reaction forces, tractions.
perideal_add_test_program(kw_tests ${CMAKE_CURRENT_LIST_DIR}/kw_tests.cc)
foreach(_t precrack_3d measurements prescribed traction_wave bad_input)
  perideal_add_test(NAME kw.${_t} COMMAND $<TARGET_FILE:kw_tests> ${_t} LABELS unit)
endforeach()
perideal_add_test(NAME kw.prescribed.np2 NPROCS 2
  COMMAND $<TARGET_FILE:kw_tests> prescribed LABELS "unit;mpi")
