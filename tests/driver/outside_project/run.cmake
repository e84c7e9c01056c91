# Configure, build and run the outside project against a PeriDEAL build tree.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY}
  -DPeriDEAL_DIR=${PERIDEAL_DIR} -DCMAKE_BUILD_TYPE=Release RESULT_VARIABLE r)
if(r)
  message(FATAL_ERROR "configure failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} RESULT_VARIABLE r)
if(r)
  message(FATAL_ERROR "build failed")
endif()
execute_process(COMMAND ${BINARY}/outside RESULT_VARIABLE r)
if(r)
  message(FATAL_ERROR "outside program failed")
endif()
