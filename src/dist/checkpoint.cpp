// Tile files of a checkpoint (see checkpoint.h).
#include "dist/checkpoint.h"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>

#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

namespace {
constexpr char kMagic[8] = {'C', 'L', 'R', 'T', 'T', 'I', 'L', '1'};
struct TileHeader {
    char magic[8];
    uint64_t key, tile, first, count;
};
}  // namespace

Checkpoint::Checkpoint(const std::string& dir, const std::string& imageName, const std::string& key, const TileGrid& grid)
    : key_(std::strtoull(key.c_str(), nullptr, 16)), grid_(grid) {
    folder_ = (fs::path(dir) / (imageName + "-" + key)).string();
    std::error_code ec;
    fs::create_directories(folder_, ec);
    if (!fs::is_directory(folder_)) throw Error(folder_ + ": cannot create the checkpoint folder", ExitCode::Output);
}

std::string Checkpoint::tilePath(size_t t) const { return (fs::path(folder_) / ("tile-" + std::to_string(t) + ".bin")).string(); }

std::vector<bool> Checkpoint::load(ImageRGB& img) const {
    // A writer killed mid-write leaves its temporary (.tile-N.bin.tmp-PID): removed once ten minutes old.
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(folder_, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(".tile-", 0) == 0 && name.find(".tmp-") != std::string::npos &&
            fs::last_write_time(e.path(), ec) < fs::file_time_type::clock::now() - std::chrono::minutes(10))
            fs::remove(e.path(), ec);
    }
    std::vector<bool> have(grid_.count(), false);
    for (size_t t = 0; t < grid_.count(); ++t) {
        const std::string path = tilePath(t);
        std::ifstream in(path, std::ios::binary);
        if (!in) continue;
        std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const size_t floats = grid_.size(t) * 3;
        TileHeader h{};
        uint64_t sum = 0;
        bool ok = b.size() == sizeof h + floats * sizeof(float) + sizeof sum;
        if (ok) {
            std::memcpy(&h, b.data(), sizeof h);
            std::memcpy(&sum, b.data() + b.size() - sizeof sum, sizeof sum);
            ok = std::memcmp(h.magic, kMagic, 8) == 0 && h.key == key_ && h.tile == t && h.first == grid_.first(t) &&
                 h.count == grid_.size(t) && sum == fnv1a64(b.data(), b.size() - sizeof sum);
        }
        if (!ok) {
            warn(path + ": damaged or foreign checkpoint tile; rendering the tile again");
            continue;
        }
        std::memcpy(&img.pixels[grid_.first(t) * 3], b.data() + sizeof h, floats * sizeof(float));
        have[t] = true;
    }
    return have;
}

void Checkpoint::store(size_t t, const ImageRGB& img) const {
    TileHeader h{};
    std::memcpy(h.magic, kMagic, 8);
    h.key = key_;
    h.tile = t;
    h.first = grid_.first(t);
    h.count = grid_.size(t);
    std::string b(reinterpret_cast<const char*>(&h), sizeof h);
    b.append(reinterpret_cast<const char*>(&img.pixels[h.first * 3]), h.count * 3 * sizeof(float));
    const uint64_t sum = fnv1a64(b.data(), b.size());
    b.append(reinterpret_cast<const char*>(&sum), sizeof sum);
    const std::string path = tilePath(t);
    writeAtomically(path, [&](const std::string& tmp) {
        int fd = openTemporaryForWrite(tmp, path);
        size_t done = 0;
        while (done < b.size()) {
            ssize_t n = ::write(fd, b.data() + done, b.size() - done);
            if (n <= 0) {
                ::close(fd);
                throw Error(path + ": cannot write checkpoint tile", ExitCode::Output);
            }
            done += size_t(n);
        }
        if (::close(fd) != 0) throw Error(path + ": cannot write checkpoint tile", ExitCode::Output);
    });
}

}  // namespace clrt
