# `hapsyn view` (HAPSYN_WITH_VIEW): its sources, Boost.Beast (headers of libboost-dev), and the
# page of web/ embedded at build time. three.js comes from npm (web/package-lock.json): when
# web/node_modules lacks it, configure runs `npm ci` once if npm is there; if that is not possible
# the build goes on and `hapsyn view` says that its page is not built and how to build it.
function(hapsyn_add_view target)
  set(web ${PROJECT_SOURCE_DIR}/web)
  set(three ${web}/node_modules/three)
  find_program(HAPSYN_NPM npm)
  if(NOT EXISTS ${three}/build/three.module.min.js AND HAPSYN_NPM)
    message(STATUS "hapsyn view: installing three.js from web/package-lock.json (npm ci)")
    execute_process(COMMAND ${HAPSYN_NPM} ci --no-audit --no-fund --loglevel=error WORKING_DIRECTORY ${web}
                    RESULT_VARIABLE npm_result OUTPUT_QUIET ERROR_VARIABLE npm_error TIMEOUT 300)
    if(NOT npm_result EQUAL 0)
      message(WARNING "hapsyn view: npm ci in ${web} failed (${npm_result}): ${npm_error}")
    endif()
  endif()
  # route|content type|file; three.js and its orbit controls copied next to the page.
  set(js "text/javascript")  # no ";" in a CMake list: view_command adds the charset
  set(assets "/|text/html|${web}/index.html" "/app.js|${js}|${web}/app.js" "/front.js|${js}|${web}/front.js"
             "/front3d.js|${js}|${web}/front3d.js" "/plots.js|${js}|${web}/plots.js" "/figure.js|${js}|${web}/figure.js")
  list(APPEND assets "/prototype.js|${js}|${web}/prototype.js")  # the virtual prototype
  set(missing "")
  if(EXISTS ${three}/build/three.module.min.js AND EXISTS ${three}/examples/jsm/controls/OrbitControls.js)
    list(APPEND assets "/three.module.js|${js}|${three}/build/three.module.min.js"
                       "/OrbitControls.js|${js}|${three}/examples/jsm/controls/OrbitControls.js")
    # A URDF's meshes (web/meshes.js): three's loaders. ColladaLoader imports TGALoader by a
    # relative path, which a report's data: copy of it cannot resolve: the copy embedded imports
    # it by the bare name of the page's import map instead (the only change).
    set(collada_source ${three}/examples/jsm/loaders/ColladaLoader.js)
    set(collada ${CMAKE_BINARY_DIR}/web-patched/ColladaLoader.js)
    file(READ ${collada_source} collada_text)
    string(FIND "${collada_text}" "'../loaders/TGALoader.js'" tga_import)
    if(tga_import EQUAL -1)
      message(FATAL_ERROR "hapsyn view: ${collada_source} no longer imports '../loaders/TGALoader.js'; update cmake/HapsynView.cmake")
    endif()
    string(REPLACE "'../loaders/TGALoader.js'" "'three/addons/loaders/TGALoader.js'" collada_text "${collada_text}")
    file(WRITE ${collada}.new "${collada_text}")
    execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${collada}.new ${collada})
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${collada_source})
    list(APPEND assets "/meshes.js|${js}|${web}/meshes.js"
                       "/loaders/STLLoader.js|${js}|${three}/examples/jsm/loaders/STLLoader.js"
                       "/loaders/ColladaLoader.js|${js}|${collada}"
                       "/loaders/TGALoader.js|${js}|${three}/examples/jsm/loaders/TGALoader.js")
  else()
    set(assets "")
    # Plain text: it becomes a C++ string literal.
    set(missing "three.js is not installed in ${web}/node_modules: run npm ci there (scripts/setup.sh installs npm) and build again")
    message(WARNING "hapsyn view: ${missing}; the program builds, `hapsyn view` reports it")
  endif()
  set(page ${CMAKE_BINARY_DIR}/web)
  set(manifest ${page}/manifest.txt)
  set(files "")
  set(lines "")
  foreach(asset IN LISTS assets)
    string(REPLACE "|" ";" parts "${asset}")
    list(GET parts 2 source)
    get_filename_component(name ${source} NAME)
    # The copy next to the page (build/web/) is what is embedded.
    configure_file(${source} ${page}/${name} COPYONLY)
    list(GET parts 0 route)
    list(GET parts 1 type)
    string(APPEND lines "${route}|${type}|${page}/${name}\n")
    list(APPEND files ${page}/${name})
  endforeach()
  file(WRITE ${manifest}.new "${lines}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${manifest}.new ${manifest})
  set(output ${CMAKE_CURRENT_BINARY_DIR}/web_assets.cpp)
  add_custom_command(OUTPUT ${output}
    COMMAND ${CMAKE_COMMAND} -DMANIFEST=${manifest} -DOUTPUT=${output} "-DMISSING=${missing}"
            -P ${PROJECT_SOURCE_DIR}/cmake/EmbedWebAssets.cmake
    DEPENDS ${manifest} ${files} ${PROJECT_SOURCE_DIR}/cmake/EmbedWebAssets.cmake
    COMMENT "Embedding the page of hapsyn view"
    VERBATIM)
  target_sources(${target} PRIVATE app/view/view_command.cpp app/view/view_data.cpp app/view/view_figure.cpp app/view/view_source.cpp
    app/view/samples_csv_reader.cpp app/view/http_server.cpp app/view/result_views.cpp app/view/report_command.cpp ${output})
  # The virtual prototype: the replay and the live frames (with the motion scene's signal
  # processing), a library of their own that benchmarks/live_frame_benchmark.cpp times too.
  add_library(hapsyn_view_prototype STATIC app/view/replay_data.cpp app/view/live_session.cpp app/view/view_json.cpp
    ${PROJECT_SOURCE_DIR}/plugins/scenes/motion/motion_signal.cpp)
  target_include_directories(hapsyn_view_prototype PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/app/view
    ${PROJECT_SOURCE_DIR}/plugins/scenes/motion)
  target_link_libraries(hapsyn_view_prototype PUBLIC hapsyn hapsyn_internal)
  target_compile_options(hapsyn_view_prototype PRIVATE ${HAPSYN_WARNINGS})
  target_sources(${target} PRIVATE app/view/socket_session.cpp)
  target_link_libraries(${target} PRIVATE hapsyn_view_prototype)
  target_sources(${target} PRIVATE app/view/view_meshes.cpp)
  target_include_directories(${target} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/app/view)
  target_compile_definitions(${target} PRIVATE HAPSYN_WITH_VIEW=1)
endfunction()
