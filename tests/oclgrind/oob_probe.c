/* oob_probe.c — negative control of the oclgrind suite (scripts/oclgrind_suite.sh): a kernel that
 * reads one element past its buffer and stores an uninitialised value. Run under the suite's oclgrind
 * settings it must produce reports; if it does not, oclgrind is not engaged and the suite fails
 * instead of passing silently. Exits 0 when the OpenCL calls succeed. */
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdio.h>

static const char* kSource =
    "__kernel void probe(__global const float* in, __global float* out, int n) {\n"
    "    int i = get_global_id(0);\n"
    "    float x;\n"
    "    if (n < 0) x = 1.0f;\n"
    "    out[i] = in[i + n] + x;\n"
    "}\n";

int main(void) {
    cl_platform_id platform;
    cl_device_id device;
    cl_int err = clGetPlatformIDs(1, &platform, NULL);
    if (err == CL_SUCCESS) err = clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 1, &device, NULL);
    if (err != CL_SUCCESS) { fprintf(stderr, "oob_probe: no OpenCL device (%d)\n", err); return 1; }
    cl_context ctx = clCreateContext(NULL, 1, &device, NULL, NULL, &err);
    cl_command_queue q = clCreateCommandQueue(ctx, device, 0, &err);
    cl_program prog = clCreateProgramWithSource(ctx, 1, &kSource, NULL, &err);
    if (clBuildProgram(prog, 1, &device, "", NULL, NULL) != CL_SUCCESS) { fprintf(stderr, "oob_probe: build failed\n"); return 1; }
    cl_kernel k = clCreateKernel(prog, "probe", &err);
    float host[4] = {1, 2, 3, 4};
    cl_mem in = clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof host, host, &err);
    cl_mem out = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, sizeof host, NULL, &err);
    int n = 1;
    clSetKernelArg(k, 0, sizeof in, &in);
    clSetKernelArg(k, 1, sizeof out, &out);
    clSetKernelArg(k, 2, sizeof n, &n);
    size_t global = 4;
    err = clEnqueueNDRangeKernel(q, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    if (err == CL_SUCCESS) err = clFinish(q);
    printf("oob_probe: kernel ran (%d)\n", err);
    return err == CL_SUCCESS ? 0 : 1;
}
