# The synthetic arm motion generator (synthetic_motion.hpp), its command-line program that writes
# share/motion/synthetic/, and its test.
target_sources(hapsyn_motion_model PRIVATE ${CMAKE_CURRENT_LIST_DIR}/synthetic_motion.cpp)
# The arm model is the shared engine (plugins/scenes/shared/human_arm_model/), not the human_arm
# scene's library.
target_link_libraries(hapsyn_motion_model PUBLIC hapsyn_human_arm_engine)

add_executable(hapsyn_make_synthetic_motion ${CMAKE_CURRENT_LIST_DIR}/make_synthetic_motion.cpp)
set_target_properties(hapsyn_make_synthetic_motion PROPERTIES OUTPUT_NAME hapsyn-make-synthetic-motion
  INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
target_link_libraries(hapsyn_make_synthetic_motion PRIVATE hapsyn_motion_model CLI11::CLI11)
target_compile_options(hapsyn_make_synthetic_motion PRIVATE ${HAPSYN_WARNINGS})

if(HAPSYN_BUILD_TESTS)
  hapsyn_add_test(synthetic_motion_test ${CMAKE_CURRENT_LIST_DIR}/synthetic_motion_test.cpp LIBRARIES hapsyn_motion_model)
endif()
