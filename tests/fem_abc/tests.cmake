perideal_add_test_program(fem_abc_tests ${CMAKE_CURRENT_LIST_DIR}/fem_abc_tests.cc)
