// kernel_args.cpp — the host's table of kernel declarations (generated from src/shared/kernel_params.h)
// and the checked binder.
#include "cl/kernel_args.h"

#include <cstring>

#include "cl/check.h"
#include "shared/device_types.h"
#include "shared/kernel_params.h"
#include "util/error.h"

namespace clrt {
namespace dev {
namespace {
// Inside clrt::dev, so that the declared type names (Bvh8Node, float4, uint, ...) resolve.
#define CLRT_HOST_PARAM_(KIND, T, name) ParamDecl{#name, ParamKind::KIND, sizeof(T)},
#define CLRT_HOST_KERNEL_(K) KernelDecl{#K, {CLRT_KERNEL_##K(CLRT_HOST_PARAM_)}},
const std::vector<KernelDecl> kTable = {
    CLRT_RENDER_KERNELS(CLRT_HOST_KERNEL_) CLRT_TONEMAP_KERNELS(CLRT_HOST_KERNEL_) CLRT_LAYOUT_KERNELS(CLRT_HOST_KERNEL_)};
#undef CLRT_HOST_PARAM_
#undef CLRT_HOST_KERNEL_
}  // namespace
}  // namespace dev

const std::vector<KernelDecl>& kernelDecls() { return dev::kTable; }

const KernelDecl& kernelDecl(const std::string& name) {
    for (const KernelDecl& k : dev::kTable)
        if (name == k.name) return k;
    throw Error("kernel " + name + " has no declaration in src/shared/kernel_params.h", ExitCode::Device);
}

KernelArgs::KernelArgs(const cl::Program& program, const char* name)
    : kernel_(CL_CPP(cl::Kernel(program, name))), decl_(&kernelDecl(name)), bound_(decl_->params.size(), false) {}

size_t KernelArgs::index(const char* name, bool buffer) const {
    const std::vector<ParamDecl>& ps = decl_->params;
    for (size_t i = 0; i < ps.size(); ++i) {
        if (std::strcmp(ps[i].name, name) != 0) continue;
        if (buffer != (ps[i].kind != ParamKind::VAL))
            throw Error(std::string("kernel ") + decl_->name + ": parameter " + name + " is " +
                            (buffer ? "a value; a buffer was bound" : "a buffer; a value was bound"),
                        ExitCode::Device);
        return i;
    }
    throw Error(std::string("kernel ") + decl_->name + " has no parameter " + name, ExitCode::Device);
}

KernelArgs& KernelArgs::set(const char* name, const cl::Buffer& buffer) {
    size_t i = index(name, true);
    CL_CPP(kernel_.setArg(cl_uint(i), buffer));
    bound_[i] = true;
    return *this;
}

KernelArgs& KernelArgs::setValue(const char* name, size_t size, const void* value) {
    size_t i = index(name, false);
    if (size != decl_->params[i].valueSize)
        throw Error(std::string("kernel ") + decl_->name + ": parameter " + name + " takes " +
                        std::to_string(decl_->params[i].valueSize) + " bytes; " + std::to_string(size) + " were bound",
                    ExitCode::Device);
    CL_CPP(kernel_.setArg(cl_uint(i), size, value));
    bound_[i] = true;
    return *this;
}

void KernelArgs::checkAllBound() const {
    for (size_t i = 0; i < bound_.size(); ++i)
        if (!bound_[i])
            throw Error(std::string("kernel ") + decl_->name + ": parameter " + decl_->params[i].name + " is not bound",
                        ExitCode::Device);
}

cl::Kernel& KernelArgs::ready() {
    if (!allBound_) {
        checkAllBound();
        allBound_ = true;
    }
    return kernel_;
}

}  // namespace clrt
