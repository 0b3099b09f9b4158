# The project's layers, enforced when CMake configures (issue 60): a folder
# may include only its own headers and those of the folders it declares it
# builds on (and theirs, transitively). An include back up, or one sideways
# that is not declared, stops the configuration with the line that has it:
#
#   app/ghost/ghost.h:71: error: app/ghost includes "app/console/x.h": it builds on
#   app/state and what they build on only (declare it ..., or move the code down)
#
# Folders are declared bottom up, each after what it builds on, so the
# declared graph has no cycle and no folder pair includes each other.

# sp_layer(FOLDER [RECURSE] [ON folder...]): FOLDER (e.g. app/ghost) builds on
# the folders listed, which must be declared before it; its *.h and *.cpp are
# checked (RECURSE: its subfolders' too, as one layer).
function(sp_layer folder)
  cmake_parse_arguments(L "RECURSE" "" "ON" ${ARGN})
  set(allowed ${folder})
  foreach(dep IN LISTS L_ON)
    get_property(known GLOBAL PROPERTY "SP_LAYER_${dep}" SET)
    if(NOT known)
      message(FATAL_ERROR "${folder}: builds on ${dep}, which is not declared before it (cmake/layers.cmake)")
    endif()
    get_property(below GLOBAL PROPERTY "SP_LAYER_${dep}")
    list(APPEND allowed ${dep} ${below})
  endforeach()
  list(REMOVE_DUPLICATES allowed)
  set_property(GLOBAL PROPERTY "SP_LAYER_${folder}" ${allowed})

  set(glob GLOB)
  if(L_RECURSE)
    set(glob GLOB_RECURSE)
  endif()
  file(${glob} sources RELATIVE ${PROJECT_SOURCE_DIR}
       ${PROJECT_SOURCE_DIR}/${folder}/*.h ${PROJECT_SOURCE_DIR}/${folder}/*.cpp)
  # The project's top folders and app/'s subfolders: an include names one of them.
  set(problems "")
  foreach(source IN LISTS sources)
    file(READ ${PROJECT_SOURCE_DIR}/${source} content)
    string(REGEX MATCHALL "#[ \t]*include[ \t]+\"(sim|net|ui|ros|app/[a-z_]+)/[^\"]+\"" includes "${content}")
    foreach(include IN LISTS includes)
      string(REGEX MATCH "\"((sim|net|ui|ros|app/[a-z_]+)/[^\"]+)\"" _ "${include}")
      set(header ${CMAKE_MATCH_1})
      if(CMAKE_MATCH_2 IN_LIST allowed)
        continue()
      endif()
      # Its line: the newlines before it, plus one.
      string(FIND "${content}" "${include}" at)
      string(SUBSTRING "${content}" 0 ${at} before)
      string(REGEX MATCHALL "\n" newlines "${before}")
      list(LENGTH newlines number)
      math(EXPR number "${number} + 1")
      string(REPLACE ";" ", " basis "${L_ON}")
      if(NOT basis)
        set(basis "nothing of ours")
      endif()
      string(APPEND problems
             "${source}:${number}: error: ${folder} includes \"${header}\": it builds on ${basis} "
             "and what they build on only (declare it in its CMakeLists.txt's sp_layer, or move the code down)\n")
    endforeach()
  endforeach()
  if(problems)
    message(FATAL_ERROR "the layers do not hold:\n${problems}")
  endif()
endfunction()
