// tonemap_settings.h — the settings of one tone mapping: a camera's Tonemap block in the scene model
// (scene/scene.h, Camera::tonemaps), the options of `clrt tonemap`, and what the host reference
// (image/tonemap.h) and the device (output/tonemap_device.h) map an image with. Header-only and
// host-only; here (beside dev::TmoKind) so that the scene model and the image module share one type.
#pragma once
#include <string>

#include "shared/device_types.h"  // dev::TmoKind, the one operator enum (host, kernels, scene model)

namespace clrt {

struct TonemapSettings {
    dev::TmoKind op = dev::TMO_PHOTOGRAPHIC;  // <TMO>
    float key = 0.18f;          // TMOOptions[0]
    float burnPercent = 1.0f;   // TMOOptions[1] (Photographic only), in [0, 100]
    float saturation = 1.0f;    // <Saturation>
    float gamma = 2.2f;         // <Gamma>
    bool srgb = false;          // <Gamma>sRGB</Gamma>: the sRGB transfer curve instead of v^(1/gamma)
    std::string extension;      // <Extension>, e.g. "_aces" (output name suffix); empty when the block names none
    double delta = 1e-6;        // the δ of the log-average (1e-6 reproduces the course; clrt tonemap --delta)
    bool truncate = true;       // 8-bit quantisation: floor (the course's) or round (--ldr-quantize, --quantize)
};

}  // namespace clrt
