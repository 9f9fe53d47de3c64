# Copies the qdem package (SRC, its subpackages too) into DST, a file only
# when it differs, and removes from DST the modules SRC no longer has (a
# module moved into a subpackage must not linger at its old path).
# cmake -DSRC=py/qdem -DDST=build/python/qdem -P py/copy_package.cmake
file(GLOB_RECURSE src RELATIVE ${SRC} ${SRC}/*.py)
file(GLOB_RECURSE dst RELATIVE ${DST} ${DST}/*.py)
foreach(f ${src})
  get_filename_component(d ${DST}/${f} DIRECTORY)
  file(MAKE_DIRECTORY ${d})
  execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${SRC}/${f} ${DST}/${f})
endforeach()
foreach(f ${dst})
  list(FIND src ${f} i)
  if(i EQUAL -1)
    file(REMOVE ${DST}/${f})
  endif()
endforeach()
