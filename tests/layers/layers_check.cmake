# cmake/layers.cmake's check on a tree of its own (cmake -DCASE=... -P):
#   declared  app/high builds on app/low and includes it: accepted
#   back_up   app/low includes app/high: refused, naming the line
#   undeclared app/high builds on app/none, never declared: refused
# The real tree is checked each time CMake configures the project.
cmake_minimum_required(VERSION 3.25)  # IN_LIST and the policies of the project
set(PROJECT_SOURCE_DIR ${CMAKE_CURRENT_BINARY_DIR}/layers_${CASE})
file(REMOVE_RECURSE ${PROJECT_SOURCE_DIR})
file(WRITE ${PROJECT_SOURCE_DIR}/app/high/b.h "#pragma once\n#include \"app/low/a.h\"\n")
if(CASE STREQUAL "back_up")
  file(WRITE ${PROJECT_SOURCE_DIR}/app/low/a.h "#pragma once\n// a comment\n#include \"app/high/b.h\"\n")
else()
  file(WRITE ${PROJECT_SOURCE_DIR}/app/low/a.h "#pragma once\n#include <vector>\n")
endif()
include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/layers.cmake)
if(CASE STREQUAL "undeclared")
  sp_layer(app/high ON app/none)
else()
  sp_layer(app/low)
  sp_layer(app/high ON app/low)
endif()
message(STATUS "layers hold")
