# clrt_embed_kernels(OUT file1 file2 ...)
# Generates OUT, a C++ file defining clrt::embeddedKernelSources(): every input file as a raw string,
# prefixed with a `#line 1 "<path relative to the source tree>"` marker so that OpenCL compiler
# messages name the real file. Regenerated whenever an input changes. The #include "..." lines between
# the files are not expanded here: src/cl/program.cpp (loadKernelSources) resolves them when a program
# is assembled, from these copies or from $CLRT_KERNEL_DIR, relative to the including file's path.
set(CLRT_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/EmbedKernelsRun.cmake)
function(clrt_embed_kernels out)
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DROOT=${CMAKE_SOURCE_DIR} "-DINPUTS=${ARGN}" -P ${CLRT_EMBED_SCRIPT}
    DEPENDS ${ARGN} ${CLRT_EMBED_SCRIPT}
    COMMENT "Embedding OpenCL kernel sources"
    VERBATIM)
endfunction()
