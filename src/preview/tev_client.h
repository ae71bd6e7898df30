// tev_client.h — `clrt render --display-server HOST:PORT`: streams each camera's image to the tev
// viewer over its TCP protocol, as pbrt-v4 does: a CreateImage packet (type 4: the image with
// channels R, G, B) when a camera starts, then UpdateImage packets (type 6, "V3": a tile with
// per-channel offsets and strides, float32 little-endian) of 128x128 tiles after each published pass.
// Packets are written from tev's documentation (its ipc.py), not from its code. Sending happens on a
// thread of its own; an update waiting to be sent is replaced by a newer one. tev not running: one
// warning, and the render goes on; a connection lost later: one warning, no more sending. The sending
// thread's CPU time per image goes to `onCost` (the preview's time budget, preview_state.h).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"

namespace clrt {

// Packet bytes (little-endian): uint32 length of the whole packet, uint8 type, then the fields.
std::string tevCreateImagePacket(const std::string& name, int width, int height, const std::vector<std::string>& channels,
                                 bool grabFocus = true);
// The UpdateImage (V3) packets of `img` in tiles of at most tile x tile pixels.
std::vector<std::string> tevUpdateImagePackets(const std::string& name, const ImageRGB& img, int tile = 128);

class TevClient {
public:
    // "HOST:PORT" (throws clrt::Error (Usage) when malformed); connects at once, with a 2 s timeout.
    explicit TevClient(const std::string& hostPort, std::function<void(double)> onCost = {});
    ~TevClient();  // sends what is queued (at most 5 s more), then closes
    TevClient(const TevClient&) = delete;
    TevClient& operator=(const TevClient&) = delete;

    bool connected() const;
    void createImage(const std::string& name, int width, int height);
    void updateImage(const std::string& name, std::shared_ptr<const ImageRGB> img);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace clrt
