# Install rules (ATMO_INSTALL, on when atmo is the top-level project):
#   cmake --install build --prefix P
# installs include/atmo/ (and include/atmo/gl/ with the GL backend), libatmo (and libatmo_gl),
# bin/atmo, the CMake package (P/lib*/cmake/atmo: find_package(atmo CONFIG)) and pkg-config files
# (atmo.pc, atmo-gl.pc). Both packages are relocatable: they find the prefix from their own path.
include(CMakePackageConfigHelpers)

set(ATMO_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/atmo CACHE STRING
  "Where the CMake package of atmo is installed, relative to the prefix")
mark_as_advanced(ATMO_INSTALL_CMAKEDIR)

install(TARGETS atmo EXPORT atmoTargets)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/atmo DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        PATTERN gl EXCLUDE)
if(TARGET atmo_gl)
  install(TARGETS atmo_gl EXPORT atmoTargets)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/atmo/gl DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/atmo)
endif()
set_target_properties(atmo_cli PROPERTIES EXPORT_NAME cli)
install(TARGETS atmo_cli EXPORT atmoTargets)

install(EXPORT atmoTargets NAMESPACE atmo:: DESTINATION ${ATMO_INSTALL_CMAKEDIR} FILE atmoTargets.cmake)
if(NOT ATMO_HAVE_GLFW)
  set(ATMO_HAVE_GLFW OFF)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/atmoConfig.cmake.in
  ${PROJECT_BINARY_DIR}/package/atmoConfig.cmake
  INSTALL_DESTINATION ${ATMO_INSTALL_CMAKEDIR})
# 0.x: a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/atmoConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES
  ${PROJECT_BINARY_DIR}/package/atmoConfig.cmake
  ${PROJECT_BINARY_DIR}/package/atmoConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/Findlibnova.cmake
  DESTINATION ${ATMO_INSTALL_CMAKEDIR})

# pkg-config. The prefix is found from the .pc file's own folder (${pcfiledir}), so that
# `cmake --install --prefix P` works for any P. A static libatmo.a needs its dependencies at the
# consumer's link, so they go into Requires/Libs (plain `pkg-config --libs atmo` links); a shared
# one keeps them private.
set(ATMO_PKGCONFIG_DIR ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(ATMO_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
  set(ATMO_PC_LIBDIR "${CMAKE_INSTALL_FULL_LIBDIR}")
  set(ATMO_PC_INCLUDEDIR "${CMAKE_INSTALL_FULL_INCLUDEDIR}")
else()
  file(RELATIVE_PATH up "/${ATMO_PKGCONFIG_DIR}" "/")
  string(REGEX REPLACE "/$" "" up "${up}")
  set(ATMO_PC_PREFIX "\${pcfiledir}/${up}")
  set(ATMO_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
  set(ATMO_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
# What libatmo links privately (src/atmo/CMakeLists.txt): oneTBB, OpenEXR, libpng have .pc
# files; libnova has none, mvec is glibc's vector maths. nlohmann_json is header-only.
set(private_requires " tbb OpenEXR libpng")
set(private_libs " -lnova")
if(CMAKE_SYSTEM_NAME STREQUAL "Linux")
  string(APPEND private_libs " -lmvec")
endif()
set(gl_private_requires " epoxy")
if(ATMO_HAVE_GLFW)
  string(APPEND gl_private_requires " glfw3")
endif()
get_target_property(atmo_type atmo TYPE)
if(atmo_type STREQUAL "STATIC_LIBRARY")
  set(ATMO_PC_REQUIRES "${private_requires}")
  set(ATMO_PC_LIBS "${private_libs}")
  set(ATMO_PC_REQUIRES_PRIVATE "")
  set(ATMO_PC_LIBS_PRIVATE "")
  set(ATMO_GL_PC_REQUIRES "${gl_private_requires}")
  set(ATMO_GL_PC_REQUIRES_PRIVATE "")
else()
  set(ATMO_PC_REQUIRES "")
  set(ATMO_PC_LIBS "")
  set(ATMO_PC_REQUIRES_PRIVATE "${private_requires}")
  set(ATMO_PC_LIBS_PRIVATE "${private_libs}")
  set(ATMO_GL_PC_REQUIRES "")
  set(ATMO_GL_PC_REQUIRES_PRIVATE "${gl_private_requires}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/atmo.pc.in ${PROJECT_BINARY_DIR}/package/atmo.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/package/atmo.pc DESTINATION ${ATMO_PKGCONFIG_DIR})
if(TARGET atmo_gl)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/atmo-gl.pc.in ${PROJECT_BINARY_DIR}/package/atmo-gl.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/package/atmo-gl.pc DESTINATION ${ATMO_PKGCONFIG_DIR})
endif()
