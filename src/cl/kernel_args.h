// kernel_args.h — binding kernel arguments by name from their one declaration
// (src/shared/kernel_params.h): no argument index is written by hand anywhere. A KernelArgs owns one
// kernel and checks every binding against the declared (name, kind, value size): a name the kernel
// does not declare, a buffer for a value (or the reverse), a value of another size, or a parameter
// left unbound throws clrt::Error (Device) naming the kernel and the parameter, before any launch.
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace clrt {

enum class ParamKind { VAL, IN, BUF };  // by value, const __global T*, __global T*

struct ParamDecl {
    const char* name;
    ParamKind kind;
    size_t valueSize;  // sizeof the type (VAL: what the host must pass; IN/BUF: the element)
};

struct KernelDecl {
    const char* name;
    std::vector<ParamDecl> params;
};

// Every kernel of every program, as declared (in the order of CLRT_*_KERNELS).
const std::vector<KernelDecl>& kernelDecls();
// The declaration of one kernel; throws clrt::Error (Device) if there is none.
const KernelDecl& kernelDecl(const std::string& name);

class KernelArgs {
public:
    KernelArgs() = default;
    // Creates kernel `name` of `program` (checked) and takes its declaration.
    KernelArgs(const cl::Program& program, const char* name);

    KernelArgs& set(const char* name, const cl::Buffer& buffer);
    template <class T> KernelArgs& set(const char* name, const T& value) { return setValue(name, sizeof(T), &value); }

    // Throws if a declared parameter has not been bound yet.
    void checkAllBound() const;
    // The kernel, every parameter bound (checked once; launches then cost nothing extra).
    cl::Kernel& ready();
    const KernelDecl& decl() const { return *decl_; }
    cl::Kernel& kernel() { return kernel_; }  // unchecked (for queries)

private:
    KernelArgs& setValue(const char* name, size_t size, const void* value);
    size_t index(const char* name, bool buffer) const;

    cl::Kernel kernel_;
    const KernelDecl* decl_ = nullptr;
    std::vector<bool> bound_;
    bool allBound_ = false;
};

// Binds every parameter of group GROUP (a CLRT_PARAMS_* macro) from the member of `obj` of the same
// name, in the group's order: CLRT_BIND_GROUP(args, CLRT_PARAMS_GEOMETRY, buffers).
#define CLRT_BIND_ROW_(KIND, T, name) clrt_bind_args_.set(#name, clrt_bind_obj_.name);
#define CLRT_BIND_GROUP(args, GROUP, obj)            \
    do {                                             \
        ::clrt::KernelArgs& clrt_bind_args_ = (args); \
        const auto& clrt_bind_obj_ = (obj);          \
        GROUP(CLRT_BIND_ROW_)                        \
    } while (0)

}  // namespace clrt
