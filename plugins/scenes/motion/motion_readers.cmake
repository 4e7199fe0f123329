# The readers of recorded hand motion (motion_recording.hpp): the hapsyn-motion CSV format, BVH
# motion capture files, and folders of both.
target_sources(hapsyn_motion_model PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/motion_csv.cpp
  ${CMAKE_CURRENT_LIST_DIR}/motion_bvh.cpp)

if(HAPSYN_BUILD_TESTS)
  # GTest::gmock for the message matchers (HasSubstr); find_package(GTest) defines it.
  hapsyn_add_test(motion_readers_test ${CMAKE_CURRENT_LIST_DIR}/motion_readers_test.cpp
    LIBRARIES hapsyn_motion_model GTest::gmock)
endif()
