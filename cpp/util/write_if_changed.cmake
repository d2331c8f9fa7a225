# write_if_changed(PATH CONTENT): writes CONTENT to PATH unless it already
# holds exactly that, so that a regenerated source file that did not change
# recompiles and relinks nothing.
function(write_if_changed path content)
  set(old "")
  if(EXISTS "${path}")
    file(READ "${path}" old)
  endif()
  if(NOT "${old}" STREQUAL "${content}")
    file(WRITE "${path}" "${content}")
  endif()
endfunction()
