# The ROS-free core as a static library `door_state_core`, from every source
# under its stage folders (the catkin build lists them by name), for the
# builds apart from catkin: test/sanitize and fuzz. Needs REPO set and PCL,
# Eigen3, nlohmann_json and yaml-cpp found; defines CORE_INCLUDES.
set(CORE_INCLUDES ${REPO}/include ${PCL_INCLUDE_DIRS} ${EIGEN3_INCLUDE_DIR})
file(GLOB CORE_SOURCES CONFIGURE_DEPENDS
  ${REPO}/src/pipeline/*.cpp ${REPO}/src/preprocess/*.cpp ${REPO}/src/segmentation/*.cpp
  ${REPO}/src/recognition/*.cpp ${REPO}/src/state/*.cpp ${REPO}/src/reconstruction/*.cpp
  ${REPO}/src/tracking/*.cpp ${REPO}/src/io/*.cpp ${REPO}/src/eval/*.cpp)
# The drive evaluation plays simulated drives: it belongs with the simulator.
list(FILTER CORE_SOURCES EXCLUDE REGEX "/src/eval/drive_eval\\.cpp$")
add_library(door_state_core STATIC ${CORE_SOURCES})
target_include_directories(door_state_core PUBLIC ${CORE_INCLUDES})
target_link_libraries(door_state_core PUBLIC ${PCL_LIBRARIES} nlohmann_json::nlohmann_json yaml-cpp)
