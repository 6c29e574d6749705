# The package as a user meets it (cmake -P; validation/CMakeLists.txt passes
# the -D variables): install the built tree into a fresh prefix, build the
# program beside this file against that prefix alone, with a CMake run of its
# own, and run it.
#
#   BUILD_DIR      the tetiso build tree to install
#   WORK_DIR       emptied first; gets prefix/ and build/
#   GENERATOR, MAKE_PROGRAM, CXX_COMPILER, BUILD_TYPE   as the tree was built
#   CXX_FLAGS      flags the program needs besides the package's (sanitizers)
cmake_minimum_required(VERSION 3.25)

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})

execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} COMMAND_ERROR_IS_FATAL ANY)

# Only the tests reach this one: it must not be part of the package.
if(EXISTS ${prefix}/include/tetiso/detail/reduce_policy.hpp)
  message(FATAL_ERROR "an internal header was installed: ${prefix}/include/tetiso/detail/reduce_policy.hpp")
endif()

# No package registry and no other prefix: what is found is what was
# installed just now, or nothing.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR} -B ${build} -G ${GENERATOR}
                        -DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
                        -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_CXX_FLAGS=${CXX_FLAGS}
                        -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCHECK_INSTALLED_HEADERS=ON
                        COMMAND_ERROR_IS_FATAL ANY)
file(STRINGS ${build}/CMakeCache.txt found REGEX "^tetiso_DIR:")
string(FIND "${found}" "=${prefix}/" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the program found another tetiso package: ${found}")
endif()

execute_process(COMMAND ${CMAKE_COMMAND} --build ${build} COMMAND_ERROR_IS_FATAL ANY)
execute_process(COMMAND ${build}/consumer COMMAND_ERROR_IS_FATAL ANY)
