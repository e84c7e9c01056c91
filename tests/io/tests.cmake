# I/O module: checkpoints, node tables, time series, ParaView output.
perideal_add_test_program(io_tests ${CMAKE_CURRENT_LIST_DIR}/io_tests.cc)

foreach(_t checkpoint node_table time_series node_output)
  perideal_add_test(NAME io.${_t} COMMAND $<TARGET_FILE:io_tests> ${_t} LABELS unit)
endforeach()

# Written and read on 2 ranks; must equal a checkpoint written on one rank.
perideal_add_test(NAME io.checkpoint.mpi2 COMMAND $<TARGET_FILE:io_tests> checkpoint
  NPROCS 2 LABELS "unit;mpi")
perideal_add_test(NAME io.node_table.mpi2 COMMAND $<TARGET_FILE:io_tests> node_table
  NPROCS 2 LABELS "unit;mpi")
perideal_add_test(NAME io.node_output.mpi2 COMMAND $<TARGET_FILE:io_tests> node_output
  NPROCS 2 LABELS "unit;mpi")
