target_sources(hapsyn_motion_model PRIVATE ${CMAKE_CURRENT_LIST_DIR}/motion_signal.cpp)
if(HAPSYN_BUILD_TESTS)
  hapsyn_add_test(motion_signal_test ${CMAKE_CURRENT_LIST_DIR}/motion_signal_test.cpp LIBRARIES hapsyn_motion_model)
endif()
