# SPDX-License-Identifier: MIT
# Helpers shared by the core's and the adapters' CMakeLists.

# A shared library exports only namespace boxtree (cmake/boxtree.map), and must resolve every
# symbol it uses at link time (not checked under the sanitizers, whose runtime only the
# executables link).
function(boxtree_export_only_boxtree target)
  set(map ${PROJECT_SOURCE_DIR}/cmake/boxtree.map)
  target_link_options(${target} PRIVATE "LINKER:--version-script=${map}")
  if(NOT BOXTREE_SANITIZE AND NOT BOXTREE_TSAN AND NOT BOXTREE_FUZZ)
    target_link_options(${target} PRIVATE "LINKER:--no-undefined")
  endif()
  set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS ${map})
endfunction()

# Writes and installs NAME.pc (cmake/boxtree.pc.in). The prefix is found from the .pc file's own
# place (${pcfiledir}), so that `cmake --install --prefix P` anywhere gives working files.
function(boxtree_install_pkgconfig name description requires libs libs_private cflags)
  set(pc_name ${name})
  set(pc_description ${description})
  set(pc_requires ${requires})
  set(pc_libs ${libs})
  set(pc_libs_private ${libs_private})
  set(pc_cflags ${cflags})
  file(RELATIVE_PATH pc_prefix_from_pcdir /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/boxtree.pc.in ${PROJECT_BINARY_DIR}/pkgconfig/${name}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${name}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endfunction()

# An engine adapter's library (engine/<component>, target boxtree_<component>, exported as
# boxtree::<component> in its own export set boxtree-<component>-targets): library properties,
# the shared library's exports, and the install of the library, its headers (with the generated
# boxtree/<component>/config.h) and boxtree-<component>.pc (which requires `requires`).
function(boxtree_adapter_library component description requires)
  set(target boxtree_${component})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON OUTPUT_NAME boxtree-${component}
    EXPORT_NAME ${component} VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  if(BUILD_SHARED_LIBS)
    boxtree_export_only_boxtree(${target})
  endif()
  if(NOT BOXTREE_INSTALL)
    return()
  endif()
  install(TARGETS ${target} EXPORT boxtree-${component}-targets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY include/boxtree/${component} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/boxtree PATTERN "*.in" EXCLUDE)
  install(FILES ${PROJECT_BINARY_DIR}/include/boxtree/${component}/config.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/boxtree/${component})
  boxtree_install_pkgconfig(boxtree-${component} "${description}" "boxtree = ${PROJECT_VERSION}, ${requires}"
    "-lboxtree-${component}" "" "")
endfunction()
