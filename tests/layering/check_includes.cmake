# Checks the include layering of src/: a file in src/<stage>/ includes ("<other>/file.hpp") only
# its own stage and the stages listed before it in the order file (src/stages.txt), and every
# folder of src/ is a listed stage. Run as
#   cmake -DSOURCE_DIR=<src> -DORDER=<stages.txt> -P check_includes.cmake
# and fails, naming each offending file, line and include, when the rule is broken.

cmake_minimum_required(VERSION 3.25)

if(NOT SOURCE_DIR OR NOT ORDER)
  message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<src> -DORDER=<stages.txt> -P check_includes.cmake")
endif()

# The order: one stage a line; blank lines and lines starting with '#' are comments.
file(STRINGS ${ORDER} lines)
set(stages "")
foreach(line IN LISTS lines)
  string(STRIP "${line}" line)
  if(line STREQUAL "" OR line MATCHES "^#")
    continue()
  endif()
  if(line IN_LIST stages)
    message(FATAL_ERROR "${ORDER}: stage '${line}' is listed twice")
  endif()
  list(APPEND stages ${line})
endforeach()

set(problems "")
file(GLOB entries LIST_DIRECTORIES true RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/*)
foreach(entry IN LISTS entries)
  if(IS_DIRECTORY ${SOURCE_DIR}/${entry} AND NOT entry IN_LIST stages)
    list(APPEND problems "src/${entry}/ is not a stage of ${ORDER}: place it in the order")
  endif()
endforeach()

set(checked 0)
foreach(stage IN LISTS stages)
  if(NOT IS_DIRECTORY ${SOURCE_DIR}/${stage})
    list(APPEND problems "${ORDER} lists '${stage}', which is not a folder of src/")
    continue()
  endif()
  list(FIND stages ${stage} rank)
  file(GLOB_RECURSE files RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/${stage}/*.hpp ${SOURCE_DIR}/${stage}/*.cpp
       ${SOURCE_DIR}/${stage}/*.h ${SOURCE_DIR}/${stage}/*.inl)
  foreach(file IN LISTS files)
    math(EXPR checked "${checked} + 1")
    file(STRINGS ${SOURCE_DIR}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
    foreach(include IN LISTS includes)
      string(REGEX REPLACE "^[^\"]*\"([^\"]*)\".*$" "\\1" path "${include}")
      # "file.hpp" without a folder is the file's own stage (or a generated file beside it).
      if(NOT path MATCHES "^([^/]+)/")
        continue()
      endif()
      set(target ${CMAKE_MATCH_1})
      list(FIND stages ${target} target_rank)
      if(target_rank EQUAL -1)
        list(APPEND problems "src/${file}: #include \"${path}\" names no stage")
      elseif(target_rank GREATER rank)
        list(APPEND problems "src/${file}: #include \"${path}\": stage '${stage}' may not include the later stage '${target}'")
      endif()
    endforeach()
  endforeach()
endforeach()

if(problems)
  list(JOIN problems "\n  " text)
  message(FATAL_ERROR "include layering broken (order: ${ORDER}):\n  ${text}")
endif()
list(LENGTH stages count)
message(STATUS "include layering: ${checked} files in ${count} stages include only their own and earlier stages")
