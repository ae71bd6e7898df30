// check.h — error checking for OpenCL calls.
// clErrorName() maps every standard cl_int code to its name (CL_OUT_OF_RESOURCES ...).
// CL_CHECK(expr) checks a C API call returning cl_int; CL_CPP(expr) evaluates an expression that uses
// the C++ bindings (which throw cl::Error) and turns a cl::Error into clrt::Error(ExitCode::Device).
// Both messages name the error, the call, and the source file and line.
#pragma once
#include <CL/opencl.hpp>

#include <string>

#include "util/error.h"

namespace clrt {

// The symbolic name of an OpenCL error code, e.g. "CL_INVALID_KERNEL_ARGS"; "CL_UNKNOWN_ERROR" if unknown.
const char* clErrorName(cl_int code);

// "OpenCL error CL_X (-n) in <what> at <file>:<line>" (file shortened to its path below src/ or tests/).
std::string clErrorMessage(cl_int code, const std::string& what, const char* file, int line);

[[noreturn]] void throwClError(cl_int code, const std::string& what, const char* file, int line);

inline void checkCl(cl_int code, const char* what, const char* file, int line) {
    if (code != CL_SUCCESS) throwClError(code, what, file, line);
}

// Converts a cl::Error from the C++ bindings (e.what() names the C function) into a clrt::Error.
Error toError(const cl::Error& e, const char* expr, const char* file, int line);

template <class F>
decltype(auto) clTry(F&& f, const char* expr, const char* file, int line) {
    try {
        return f();
    } catch (const cl::Error& e) {
        throw toError(e, expr, file, line);
    }
}

}  // namespace clrt

// Check a C API call: CL_CHECK(clFinish(queue)).
#define CL_CHECK(expr) ::clrt::checkCl((expr), #expr, __FILE__, __LINE__)
// Evaluate a C++-bindings expression, converting cl::Error: auto buf = CL_CPP(cl::Buffer(ctx, flags, n)).
#define CL_CPP(expr) ::clrt::clTry([&]() -> decltype(auto) { return expr; }, #expr, __FILE__, __LINE__)
