/* fill_as_write.c — LD_PRELOAD shim for the oclgrind suite (scripts/oclgrind_suite.sh): turns
 * clEnqueueFillBuffer into a blocking clEnqueueWriteBuffer of the repeated pattern. Oclgrind 21.10's
 * uninitialised-value check does not count a fill as initialising the buffer (a buffer zeroed by a
 * fill and then read reports "Uninitialized value written to global memory"), which would hide real
 * reports among false ones. Only used under oclgrind; clrt itself is unchanged. */
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdlib.h>
#include <string.h>

CL_API_ENTRY cl_int CL_API_CALL clEnqueueFillBuffer(cl_command_queue queue, cl_mem buffer, const void* pattern,
                                                    size_t patternSize, size_t offset, size_t size,
                                                    cl_uint numEvents, const cl_event* waitList, cl_event* event) {
    if (!pattern || patternSize == 0 || size % patternSize != 0) return CL_INVALID_VALUE;
    unsigned char* host = malloc(size ? size : 1);
    if (!host) return CL_OUT_OF_HOST_MEMORY;
    for (size_t i = 0; i < size; i += patternSize) memcpy(host + i, pattern, patternSize);
    cl_int err = clEnqueueWriteBuffer(queue, buffer, CL_TRUE, offset, size, host, numEvents, waitList, event);
    free(host);
    return err;
}
