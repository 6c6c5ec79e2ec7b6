# The installed library (docs/getting-started.md, "Install"): shared libraries linked from
# the objects of the static layers (no source is compiled twice, and each layer's code and
# static state lives in exactly one .so), the public headers of each component, and the
# CMake package find_package(metariver CONFIG) reads:
#   metariver::metariver  libmetariver.so         terrain, solvers, field, surface, scene,
#                                                 io, water queries, the C API (mr_capi)
#   metariver::render     libmetariver_render.so  renderer, headless GL, GPU stages
#   metariver::export     libmetariver_export.so  export sessions, glTF, VDB
# Only glm reaches a user (the public headers include it); TBB, fmt, toml++, Bullet,
# OpenVDB, tinygltf and epoxy stay private dependencies of the .so files. The tests and
# the program keep linking the static layers. Included at the end of src/CMakeLists.txt,
# where the layers and their imported dependencies are in scope.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# The public headers, per component: the one list of what is installed. A header of
# include/metariver/ in none of these lists is not installed (kept in the last list with
# its reason); configuring fails when a header is in no list, or includes a header that
# its component cannot see.
set(METARIVER_CORE_HEADERS
  metariver.h water_query.h bodies.h core.h terrain.h drainage.h particles.h checkpoints.h emitters.h
  neighbor_grid.h solver.h solver_parts.h solver_registry.h pbf_solver.h spring_solver.h swe_solver.h hybrid_solver.h
  bullet_solver.h foam.h field.h sparse_field.h surface.h scene.h scene_keys.h scene_view.h io.h)
set(METARIVER_RENDER_HEADERS render.h gl_context.h gpu_pbf.h gpu_field.h)
set(METARIVER_EXPORT_HEADERS export.h)
set(METARIVER_UNINSTALLED_HEADERS
  workloads.h)  # the benchmark workloads that tests, bench/ and the program share

# Each header is in one list; each listed header exists and includes only headers of
# its own component or the core.
file(GLOB _mr_all_headers RELATIVE ${PROJECT_SOURCE_DIR}/include/metariver ${PROJECT_SOURCE_DIR}/include/metariver/*.h)
foreach(_h IN LISTS _mr_all_headers)
  set(_n 0)
  foreach(_list CORE RENDER EXPORT UNINSTALLED)
    if(_h IN_LIST METARIVER_${_list}_HEADERS)
      math(EXPR _n "${_n} + 1")
    endif()
  endforeach()
  if(NOT _n EQUAL 1)
    message(FATAL_ERROR "include/metariver/${_h} is in ${_n} of the header lists of cmake/metariver_install.cmake (must be in one)")
  endif()
endforeach()
foreach(_list CORE RENDER EXPORT)
  foreach(_h IN LISTS METARIVER_${_list}_HEADERS)
    if(NOT _h IN_LIST _mr_all_headers)
      message(FATAL_ERROR "cmake/metariver_install.cmake: METARIVER_${_list}_HEADERS names ${_h}, which include/metariver/ does not hold")
    endif()
    file(STRINGS ${PROJECT_SOURCE_DIR}/include/metariver/${_h} _includes REGEX "^#include <metariver/")
    foreach(_inc IN LISTS _includes)
      string(REGEX REPLACE "^#include <metariver/([^>]+)>.*" "\\1" _inc "${_inc}")
      if(NOT _inc IN_LIST METARIVER_CORE_HEADERS AND NOT _inc IN_LIST METARIVER_${_list}_HEADERS)
        message(FATAL_ERROR "include/metariver/${_h} (installed with ${_list}) includes metariver/${_inc}, which that component does not install")
      endif()
    endforeach()
  endforeach()
endforeach()
list(TRANSFORM METARIVER_CORE_HEADERS PREPEND ${PROJECT_SOURCE_DIR}/include/metariver/)
list(TRANSFORM METARIVER_RENDER_HEADERS PREPEND ${PROJECT_SOURCE_DIR}/include/metariver/)
list(TRANSFORM METARIVER_EXPORT_HEADERS PREPEND ${PROJECT_SOURCE_DIR}/include/metariver/)

# The shared libraries check that every symbol they use resolves (not under the
# sanitizers: their runtime is linked into executables only).
set(_mr_no_undefined -Wl,--no-undefined)
if(METARIVER_SANITIZE OR METARIVER_FUZZ OR CMAKE_CXX_FLAGS MATCHES "-fsanitize")
  set(_mr_no_undefined)
endif()

# metariver_shared_library(TARGET OUTPUT_NAME EXPORT_NAME LAYERS...): a shared library of
# the layers' objects, its version and SONAME from the project's, found beside its peers.
function(metariver_shared_library target output export_name)
  add_library(${target} SHARED)
  foreach(layer IN LISTS ARGN)
    target_sources(${target} PRIVATE $<TARGET_OBJECTS:${layer}>)
  endforeach()
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${output} EXPORT_NAME ${export_name} LINKER_LANGUAGE CXX
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN")
  target_link_options(${target} PRIVATE ${_mr_no_undefined})
  add_library(metariver::${export_name} ALIAS ${target})
endfunction()

# The core: every object of its layers (and of mr_capi, the C API, once it exists). The
# layers are linked too, for their private dependencies (TBB, fmt, toml++, libturbojpeg,
# Bullet): their objects are all in the library already, so no member is taken twice.
set(_mr_core_layers mr_stb mr_terrain mr_particles mr_field mr_surface mr_swe mr_scene mr_io)
if(METARIVER_WITH_BULLET)
  list(APPEND _mr_core_layers mr_bullet)
endif()
metariver_shared_library(metariver_lib metariver metariver ${_mr_core_layers})
target_sources(metariver_lib PRIVATE $<$<TARGET_EXISTS:mr_capi>:$<TARGET_OBJECTS:mr_capi>>)
target_link_libraries(metariver_lib PRIVATE ${_mr_core_layers} $<$<TARGET_EXISTS:mr_capi>:mr_capi>)
target_link_libraries(metariver_lib PUBLIC glm::glm)
target_include_directories(metariver_lib INTERFACE
  $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_compile_features(metariver_lib INTERFACE cxx_std_20)
install(TARGETS metariver_lib EXPORT metariver-targets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES ${METARIVER_CORE_HEADERS} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/metariver)
install(EXPORT metariver-targets NAMESPACE metariver:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/metariver)

# The components link the core library for everything below them, their own layers'
# objects, and only their own third-party libraries (never a core layer: its code would
# be in two libraries).
set(METARIVER_INSTALLED_COMPONENTS)
if(METARIVER_WITH_RENDER)
  metariver_shared_library(metariver_render metariver_render render mr_gl mr_render mr_gpu)
  target_link_libraries(metariver_render PUBLIC metariver_lib PRIVATE PkgConfig::EPOXY fmt::fmt TBB::tbb ${CMAKE_DL_LIBS})
  list(APPEND METARIVER_INSTALLED_COMPONENTS render)
endif()
if(METARIVER_WITH_EXPORT)
  metariver_shared_library(metariver_export metariver_export export mr_export)
  target_link_libraries(metariver_export PUBLIC metariver_lib PRIVATE TinyGLTF::TinyGLTF OpenVDB::openvdb fmt::fmt)
  list(APPEND METARIVER_INSTALLED_COMPONENTS export)
endif()
foreach(_c IN LISTS METARIVER_INSTALLED_COMPONENTS)
  string(TOUPPER ${_c} _C)
  install(TARGETS metariver_${_c} EXPORT metariver-${_c}-targets LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(FILES ${METARIVER_${_C}_HEADERS} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/metariver)
  install(EXPORT metariver-${_c}-targets NAMESPACE metariver:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/metariver)
endforeach()
set(METARIVER_INSTALLED_COMPONENTS ${METARIVER_INSTALLED_COMPONENTS} PARENT_SCOPE)  # tests/install

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/metariver-config.cmake.in
  ${PROJECT_BINARY_DIR}/metariver-config.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/metariver)
# 0.x: a new minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/metariver-config-version.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/metariver-config.cmake ${PROJECT_BINARY_DIR}/metariver-config-version.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/metariver)
