# gausstrack_simbody_arm: Simbody's side of the peer (simbody_arm.cpp), for the peer benchmark and
# its test. Simbody 3.7's headers do not compile as C++20: this library is C++17 behind plain types.
include_guard(GLOBAL)
add_library(gausstrack_simbody_arm STATIC ${CMAKE_CURRENT_LIST_DIR}/simbody_arm.cpp)
set_target_properties(gausstrack_simbody_arm PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON)
target_include_directories(gausstrack_simbody_arm PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(gausstrack_simbody_arm PRIVATE ${Simbody_LIBRARIES})
# Debian's Simbody is built without NDEBUG, and its headers' inline code differs with it (a
# release build's -DNDEBUG makes realizeTopology crash): this file is compiled as the library was.
target_compile_options(gausstrack_simbody_arm PRIVATE -UNDEBUG)
