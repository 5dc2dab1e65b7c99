# Script mode, run at build time by cairn_add_man_pages (cmake/CairnInstall.cmake):
#   cmake -DCAIRN=<cairn> -DHELP2MAN=<help2man> -DOUT=<dir> -DVERSION=<x.y.z> -P cairn_man_pages.cmake
# Writes OUT/cairn.1.gz from `cairn --help` and OUT/cairn-<command>.1.gz from `cairn <command> --help`
# for every command `cairn --help` lists, as git names git-commit(1).
foreach(variable CAIRN HELP2MAN OUT VERSION)
  if(NOT ${variable})
    message(FATAL_ERROR "cairn_man_pages.cmake: -D${variable}=... is required")
  endif()
endforeach()

execute_process(COMMAND "${CAIRN}" --help OUTPUT_VARIABLE help RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "cairn_man_pages.cmake: '${CAIRN} --help' failed (${status})")
endif()

# The commands: the lines "  <name>  <description>" after "Subcommands:".
string(REPLACE ";" "," help "${help}")
string(REPLACE "\n" ";" lines "${help}")
set(commands "")
set(in_commands FALSE)
foreach(line IN LISTS lines)
  if(line MATCHES "^Subcommands:")
    set(in_commands TRUE)
  elseif(in_commands AND line MATCHES "^  ([a-z0-9][a-z0-9-]*)  +(.+)$")
    list(APPEND commands "${CMAKE_MATCH_1}")
    set(description_${CMAKE_MATCH_1} "${CMAKE_MATCH_2}")
  elseif(in_commands AND NOT line MATCHES "^ ")
    set(in_commands FALSE)
  endif()
endforeach()
if(NOT commands)
  message(FATAL_ERROR "cairn_man_pages.cmake: no commands found in '${CAIRN} --help'")
endif()

file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}/bin")

# help2man names a page after the program it runs: `cairn-<command>` is a symbolic link to cairn
# (cairn finds cairn-suite beside its real file, through /proc/self/exe).
set(see_also "")
foreach(command IN LISTS commands)
  string(APPEND see_also ".BR cairn-${command} (1),\n")
endforeach()
string(REGEX REPLACE ",\n$" "\n" see_also "${see_also}")
file(WRITE "${OUT}/bin/see_also.h2m" "[SEE ALSO]\n${see_also}")
file(WRITE "${OUT}/bin/see_cairn.h2m" "[SEE ALSO]\n.BR cairn (1)\n")

function(help2man page program help_option name include)
  execute_process(
    COMMAND "${HELP2MAN}" --no-info "--version-string=${VERSION}" "--help-option=${help_option}"
            "--name=${name}" "--include=${include}" "--output=${OUT}/${page}.1" "${program}"
    RESULT_VARIABLE status ERROR_VARIABLE error)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "cairn_man_pages.cmake: help2man failed for ${page}: ${error}")
  endif()
endfunction()

help2man(cairn "${CAIRN}" "--help" "SLAM that tells you how good its answer is" "${OUT}/bin/see_also.h2m")
foreach(command IN LISTS commands)
  file(CREATE_LINK "${CAIRN}" "${OUT}/bin/cairn-${command}" SYMBOLIC)
  help2man("cairn-${command}" "${OUT}/bin/cairn-${command}" "${command} --help" "${description_${command}}"
           "${OUT}/bin/see_cairn.h2m")
endforeach()
file(REMOVE_RECURSE "${OUT}/bin")
# Compressed, as Debian policy 12.1 wants installed man pages (man reads them as they are).
file(GLOB pages "${OUT}/*.1")
foreach(page IN LISTS pages)
  file(ARCHIVE_CREATE OUTPUT "${page}.gz" PATHS "${page}" FORMAT raw COMPRESSION GZip)
  file(REMOVE "${page}")
endforeach()
list(LENGTH commands count)
message(STATUS "cairn: ${count} command man pages and cairn.1 in ${OUT}")
