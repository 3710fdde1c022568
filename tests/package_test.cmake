# The steps of the ctest cases labelled `package` (tests/CMakeLists.txt), in script mode:
#
#   cmake -DSTEP=install|cmake|pkg-config|subdirectory -DATMO_BINARY_DIR=... -DATMO_SOURCE_DIR=...
#         -DPREFIX=... -DWORK=... -DLIBDIR=lib -DGENERATOR=Ninja -DCXX=c++ -DGL=ON|OFF -P package_test.cmake
#
# install       `cmake --install` of this build into PREFIX (emptied first), then checks that the
#               headers, libraries, program, CMake package and pkg-config files are there, that no
#               private header is, and that the installed `atmo` runs.
# cmake         configures and builds tests/consumer (find_package(atmo CONFIG REQUIRED)) in WORK
#               against PREFIX alone, and checks that it found the package there.
# pkg-config    compiles and links tests/consumer/main.cc with `pkg-config --cflags --libs atmo`
#               (atmo-gl with GL) and runs it.
# subdirectory  configures tests/consumer_subdirectory (atmo through add_subdirectory, no build
#               type), whose CMakeLists.txt checks that atmo leaves the parent alone.
cmake_minimum_required(VERSION 3.25)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT result EQUAL 0)
    list(JOIN ARGN " " command)
    message(FATAL_ERROR "failed (${result}): ${command}\n${output}")
  endif()
  set(run_output "${output}" PARENT_SCOPE)
endfunction()

if(STEP STREQUAL "install")
  file(REMOVE_RECURSE ${PREFIX})
  run(${CMAKE_COMMAND} --install ${ATMO_BINARY_DIR} --prefix ${PREFIX})
  set(expected
    include/atmo/model.h include/atmo/parameters.h include/atmo/render.h include/atmo/image.h
    ${LIBDIR}/libatmo.a bin/atmo
    ${LIBDIR}/cmake/atmo/atmoConfig.cmake ${LIBDIR}/cmake/atmo/atmoConfigVersion.cmake
    ${LIBDIR}/cmake/atmo/atmoTargets.cmake ${LIBDIR}/cmake/atmo/Findlibnova.cmake
    ${LIBDIR}/pkgconfig/atmo.pc)
  if(GL)
    list(APPEND expected include/atmo/gl/context.h include/atmo/gl/hillaire_gl.h include/atmo/gl/elek_gl.h
                         ${LIBDIR}/libatmo_gl.a ${LIBDIR}/pkgconfig/atmo-gl.pc)
  endif()
  foreach(file IN LISTS expected)
    if(NOT EXISTS ${PREFIX}/${file})
      message(FATAL_ERROR "cmake --install did not install ${file}")
    endif()
  endforeach()
  # Only include/atmo's public headers: nothing of src/ (shared.h, the models', the backend's own).
  file(GLOB_RECURSE installed RELATIVE ${PREFIX}/include ${PREFIX}/include/*)
  foreach(file IN LISTS installed)
    if(NOT EXISTS ${ATMO_SOURCE_DIR}/include/${file})
      message(FATAL_ERROR "installed a header that is not in include/: ${file}")
    endif()
  endforeach()
  run(${PREFIX}/bin/atmo presets)
  list(LENGTH installed count)
  message(STATUS "installed ${count} headers; bin/atmo presets:\n${run_output}")

elseif(STEP STREQUAL "cmake")
  file(REMOVE_RECURSE ${WORK})
  run(${CMAKE_COMMAND} -S ${ATMO_SOURCE_DIR}/tests/consumer -B ${WORK} -G ${GENERATOR}
      -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_BUILD_TYPE=Release)
  message(STATUS "${run_output}")
  file(STRINGS ${WORK}/CMakeCache.txt atmo_dir REGEX "^atmo_DIR:")
  string(FIND "${atmo_dir}" "${PREFIX}/" at)
  if(NOT at GREATER -1)
    message(FATAL_ERROR "the consumer found atmo outside ${PREFIX}: ${atmo_dir}")
  endif()
  run(${CMAKE_COMMAND} --build ${WORK} -j2)

elseif(STEP STREQUAL "pkg-config")
  find_program(PKG_CONFIG pkg-config REQUIRED)
  set(ENV{PKG_CONFIG_PATH} ${PREFIX}/${LIBDIR}/pkgconfig)
  set(package atmo)
  set(defines "")
  if(GL)
    set(package atmo-gl)
    set(defines -DATMO_CONSUMER_GL)
  endif()
  run(${PKG_CONFIG} --cflags --libs ${package})
  string(STRIP "${run_output}" flags)
  message(STATUS "pkg-config --cflags --libs ${package}: ${flags}")
  separate_arguments(flags UNIX_COMMAND "${flags}")
  file(MAKE_DIRECTORY ${WORK})
  # -std=c++20: the language of atmo's headers, which a pkg-config consumer chooses itself.
  run(${CXX} -std=c++20 ${defines} ${ATMO_SOURCE_DIR}/tests/consumer/main.cc ${flags} -o ${WORK}/atmo_consumer)
  run(${WORK}/atmo_consumer)
  message(STATUS "${run_output}")

elseif(STEP STREQUAL "subdirectory")
  file(REMOVE_RECURSE ${WORK})
  run(${CMAKE_COMMAND} -S ${ATMO_SOURCE_DIR}/tests/consumer_subdirectory -B ${WORK} -G ${GENERATOR}
      -DCMAKE_CXX_COMPILER=${CXX} -DATMO_SOURCE_DIR=${ATMO_SOURCE_DIR})
  message(STATUS "${run_output}")

else()
  message(FATAL_ERROR "unknown STEP '${STEP}'")
endif()
