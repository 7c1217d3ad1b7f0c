# SPDX-License-Identifier: MIT
# The installed package as a user meets it (cmake -P). Installs the build into a scratch prefix, then:
#  1. the consumer project (CMakeLists.txt here) finds boxtree with the built components, builds the
#     core program and the engine examples (engine/*/examples), and runs them;
#  2. the same programs compiled with plain `c++ $(pkg-config --cflags --libs boxtree[-bullet|-ode])`;
#  3. shared builds: the SONAME comes from the version, only namespace boxtree is exported, and
#     the consumer does not link the private dependencies (Assimp, libccd);
#  4. what must fail, fails with a message that says what to do: a component that was not built,
#     a component that does not exist, a Bullet precision other than the adapter's (at configure
#     time and at compile time).
#  5. boxtree as a subproject (add_subdirectory): only its libraries by default.
# Variables: BINARY_DIR (the build to install), SOURCE_DIR (this folder), BOXTREE_SOURCE_DIR (the
# repository), EXAMPLES_DIR (engine/),
# WORK_DIR, BUILD_TYPE, CXX, COMPONENTS (comma-separated), SHARED (ON/OFF), BULLET_DOUBLE (0/1),
# FLAGS (compile and link flags, e.g. the sanitizers').
cmake_minimum_required(VERSION 3.16)  # script mode: the policies of this version (IN_LIST)
string(REPLACE "," ";" COMPONENTS "${COMPONENTS}")  # given comma-separated
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "failed (${result}): ${ARGN}")
  endif()
endfunction()
# Runs a command that must fail, and checks that its output contains `expected`.
function(must_fail what expected)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(result EQUAL 0)
    message(FATAL_ERROR "${what}: succeeded, should have failed: ${ARGN}")
  endif()
  string(REPLACE "\n" " " all "${out} ${err}")
  string(REGEX REPLACE " +" " " all "${all}")
  string(FIND "${all}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${what}: failed without saying '${expected}':\n${out}\n${err}")
  endif()
  message(STATUS "ok, refused as it should be: ${what}")
endfunction()

step(${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix})
set(programs consumer)
if(bullet IN_LIST COMPONENTS)
  list(APPEND programs hello_bullet)
endif()
if(ode IN_LIST COMPONENTS)
  list(APPEND programs hello_ode)
endif()

# 1. find_package
string(REPLACE ";" "," components_arg "${COMPONENTS}")
set(configure ${CMAKE_COMMAND} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
    -DCMAKE_CXX_COMPILER=${CXX} "-DCMAKE_CXX_FLAGS=${FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${FLAGS}"
    -DEXAMPLES_DIR=${EXAMPLES_DIR})
step(${configure} -S ${SOURCE_DIR} -B ${WORK_DIR}/build "-DCONSUMER_COMPONENTS=${components_arg}")
step(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
foreach(program IN LISTS programs)
  step(${WORK_DIR}/build/${program})
endforeach()

# 2. pkg-config
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} "${prefix}/lib/pkgconfig:$ENV{PKG_CONFIG_PATH}")
file(GLOB pc_dirs ${prefix}/lib*/pkgconfig ${prefix}/lib/*/pkgconfig)
foreach(dir IN LISTS pc_dirs)
  set(ENV{PKG_CONFIG_PATH} "${dir}:$ENV{PKG_CONFIG_PATH}")
endforeach()
separate_arguments(flag_list UNIX_COMMAND "${FLAGS}")
set(sources_consumer ${SOURCE_DIR}/main.cpp)
set(module_consumer boxtree)
set(sources_hello_bullet ${EXAMPLES_DIR}/bullet/examples/hello_bullet.cpp)
set(module_hello_bullet boxtree-bullet)
set(sources_hello_ode ${EXAMPLES_DIR}/ode/examples/hello_ode.cpp)
set(module_hello_ode boxtree-ode)
foreach(program IN LISTS programs)
  set(module ${module_${program}})
  execute_process(COMMAND ${PKG_CONFIG} --cflags ${module} OUTPUT_VARIABLE cflags RESULT_VARIABLE r1
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  execute_process(COMMAND ${PKG_CONFIG} --libs ${module} OUTPUT_VARIABLE libs RESULT_VARIABLE r2
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT r1 EQUAL 0 OR NOT r2 EQUAL 0)
    message(FATAL_ERROR "pkg-config ${module} failed (PKG_CONFIG_PATH=$ENV{PKG_CONFIG_PATH})")
  endif()
  message(STATUS "pkg-config ${module}: ${cflags} | ${libs}")
  separate_arguments(cflags UNIX_COMMAND "${cflags}")
  separate_arguments(libs UNIX_COMMAND "${libs}")
  step(${CXX} -std=c++17 ${flag_list} ${cflags} ${sources_${program}} -o ${WORK_DIR}/pc_${program} ${libs}
       -Wl,-rpath,${prefix}/lib)
  step(${WORK_DIR}/pc_${program})
endforeach()

# 3. shared libraries
if(SHARED)
  file(GLOB core_lib ${prefix}/lib*/libboxtree.so.*.*.* ${prefix}/lib/*/libboxtree.so.*.*.*)
  list(GET core_lib 0 core_lib)
  execute_process(COMMAND readelf -d ${core_lib} OUTPUT_VARIABLE dyn)
  string(REGEX MATCH "Library soname: \\[([^]]*)\\]" _ "${dyn}")
  set(soname "${CMAKE_MATCH_1}")
  if(NOT soname MATCHES "^libboxtree\\.so\\.[0-9]+\\.[0-9]+$")
    message(FATAL_ERROR "SONAME of ${core_lib} is '${soname}', expected libboxtree.so.MAJOR.MINOR")
  endif()
  message(STATUS "SONAME ${soname}")
  execute_process(COMMAND nm -D -C --defined-only ${core_lib} OUTPUT_VARIABLE exported)
  string(REGEX MATCHALL "\n[0-9a-f]+ [A-Za-z] [^\n]*" symbols "\n${exported}")
  list(LENGTH symbols count)
  set(foreign 0)
  foreach(symbol IN LISTS symbols)
    if(NOT symbol MATCHES "boxtree::")
      math(EXPR foreign "${foreign} + 1")
      if(foreign LESS 10)
        message(STATUS "exported but not boxtree's: ${symbol}")
      endif()
    endif()
  endforeach()
  if(foreign GREATER 0 OR count LESS 50)
    message(FATAL_ERROR "libboxtree exports ${count} symbols, ${foreign} of them outside namespace boxtree")
  endif()
  message(STATUS "libboxtree exports ${count} symbols, all in namespace boxtree")
  execute_process(COMMAND readelf -d ${WORK_DIR}/build/consumer OUTPUT_VARIABLE needed)
  if(needed MATCHES "libassimp|libccd")
    message(FATAL_ERROR "the consumer links a private dependency of boxtree:\n${needed}")
  endif()
endif()

# 4. refusals
if(bullet IN_LIST COMPONENTS)
  # The other precision, in the file that includes the adapter's headers: a compile-time error.
  execute_process(COMMAND ${PKG_CONFIG} --cflags boxtree-bullet OUTPUT_VARIABLE cflags OUTPUT_STRIP_TRAILING_WHITESPACE)
  separate_arguments(cflags UNIX_COMMAND "${cflags}")
  if(BULLET_DOUBLE)
    list(REMOVE_ITEM cflags -DBT_USE_DOUBLE_PRECISION)
    set(wrong "")
  else()
    set(wrong -DBT_USE_DOUBLE_PRECISION)
  endif()
  must_fail("compiling hello_bullet for the other Bullet precision" "boxtree::bullet was built for"
            ${CXX} -std=c++17 -fsyntax-only ${cflags} ${wrong} ${EXAMPLES_DIR}/bullet/examples/hello_bullet.cpp)
  if(NOT BULLET_DOUBLE)
    must_fail("a project that defines BT_USE_DOUBLE_PRECISION, with a single-precision adapter"
              "configure boxtree with -DBOXTREE_BULLET_DOUBLE=ON"
              ${configure} -S ${SOURCE_DIR} -B ${WORK_DIR}/build-double -DCONSUMER_COMPONENTS=bullet -DCONSUMER_DEFINE_DOUBLE=ON)
  endif()
endif()
must_fail("a component that does not exist" "boxtree has no component 'physx'"
          ${configure} -S ${SOURCE_DIR} -B ${WORK_DIR}/build-unknown -DCONSUMER_COMPONENTS=physx)
# An install without an adapter: its targets file is absent.
file(GLOB targets_files ${prefix}/lib*/cmake/boxtree/boxtree-ode-targets*.cmake ${prefix}/lib/*/cmake/boxtree/boxtree-ode-targets*.cmake)
if(targets_files)
  file(REMOVE ${targets_files})
endif()
must_fail("a component that was not built" "configure boxtree with -DBOXTREE_BUILD_ODE=ON"
          ${configure} -S ${SOURCE_DIR} -B ${WORK_DIR}/build-no-ode -DCONSUMER_COMPONENTS=ode)
# 5. add_subdirectory from a parent project: configured only (the build would repeat this one).
if(bullet IN_LIST COMPONENTS AND ode IN_LIST COMPONENTS)
  step(${CMAKE_COMMAND} -S ${SOURCE_DIR}/subproject -B ${WORK_DIR}/subproject -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
       -DCMAKE_CXX_COMPILER=${CXX} -DBOXTREE_SOURCE_DIR=${BOXTREE_SOURCE_DIR} -DEXAMPLES_DIR=${EXAMPLES_DIR})
endif()
message(STATUS "package_consumer: all checks passed (${programs}; shared ${SHARED})")
