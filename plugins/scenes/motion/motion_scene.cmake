target_sources(hapsyn_motion_model PRIVATE ${CMAKE_CURRENT_LIST_DIR}/motion_scene.cpp)
hapsyn_add_plugin(motion SOURCES ${CMAKE_CURRENT_LIST_DIR}/plugin.cpp LIBRARIES hapsyn_motion_model)
if(HAPSYN_BUILD_TESTS)
  hapsyn_add_test(motion_scene_test ${CMAKE_CURRENT_LIST_DIR}/motion_scene_test.cpp LIBRARIES hapsyn_motion_model)
  add_dependencies(motion_scene_test hapsyn_plugin_motion)
endif()
if(HAPSYN_BUILD_TESTS)
  # The validation end to end: motion scene + haptic6r + motion_feasibility through a study.
  hapsyn_add_test(motion_validation_test ${CMAKE_CURRENT_LIST_DIR}/motion_validation_test.cpp LIBRARIES hapsyn_motion_model)
  add_dependencies(motion_validation_test hapsyn_plugin_motion hapsyn_plugin_haptic6r hapsyn_plugin_motion_feasibility
    hapsyn_plugin_evaluate hapsyn_plugin_human_arm)
endif()
