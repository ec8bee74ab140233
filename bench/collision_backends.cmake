# collision_backends: times MuJoCo, FCL and Bullet collision detection on the same scenes and
# checks their manifolds and depths (results and decision: docs/collision-backend.md).
# include() this file from bench/CMakeLists.txt; it adds the `collision_backends` executable when
# FCL 0.7 and the double-precision Bullet build (libbullet-dev's -float64 libraries) are found.
#
# Everything runs inside a function so that Bullet's float64 config does not overwrite BULLET_*
# variables another find_package(Bullet) set in the including scope.
function(rigidtouch_add_collision_backends_bench)
  if(NOT TARGET Eigen3::Eigen)
    find_package(Eigen3 3.3 REQUIRED NO_MODULE)
  endif()
  if(NOT TARGET mujoco::mujoco)
    find_package(mujoco REQUIRED)
  endif()
  find_package(fcl 0.7 QUIET)
  find_package(Bullet QUIET CONFIG CONFIGS BulletConfig-float64.cmake)
  if(NOT fcl_FOUND OR NOT Bullet_FOUND OR NOT BULLET_DEFINITIONS MATCHES "BT_USE_DOUBLE_PRECISION")
    message(STATUS "collision_backends: needs FCL 0.7 (libfcl-dev) and double-precision Bullet "
                   "(libbullet-dev); not built")
    return()
  endif()
  set(bullet_lib_dir ${BULLET_ROOT_DIR}/${BULLET_LIBRARY_DIRS})
  find_library(RIGIDTOUCH_BULLET_COLLISION_F64 BulletCollision-float64 HINTS ${bullet_lib_dir})
  find_library(RIGIDTOUCH_BULLET_LINEARMATH_F64 LinearMath-float64 HINTS ${bullet_lib_dir})
  if(NOT RIGIDTOUCH_BULLET_COLLISION_F64 OR NOT RIGIDTOUCH_BULLET_LINEARMATH_F64)
    message(STATUS "collision_backends: BulletCollision-float64 / LinearMath-float64 not found; "
                   "not built")
    return()
  endif()

  set(bench_dir ${CMAKE_CURRENT_FUNCTION_LIST_DIR})
  add_executable(collision_backends ${bench_dir}/collision_backends.cc)
  target_include_directories(collision_backends PRIVATE ${bench_dir}/../include)
  target_include_directories(collision_backends SYSTEM PRIVATE
                             ${BULLET_ROOT_DIR}/${BULLET_INCLUDE_DIR})
  # must match the -float64 libraries: btScalar is double (checked by a static_assert)
  target_compile_definitions(collision_backends PRIVATE BT_USE_DOUBLE_PRECISION)
  target_link_libraries(collision_backends PRIVATE
                        Eigen3::Eigen mujoco::mujoco fcl
                        ${RIGIDTOUCH_BULLET_COLLISION_F64} ${RIGIDTOUCH_BULLET_LINEARMATH_F64})
  if(TARGET rigidtouch_warnings)
    target_link_libraries(collision_backends PRIVATE rigidtouch_warnings)
  endif()
endfunction()

rigidtouch_add_collision_backends_bench()
