// tev_client.cpp — tev's TCP protocol and the sending thread (see tev_client.h). Reads no scene element.
#include "preview/tev_client.h"

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <csignal>
#include <cstring>
#include <deque>
#include <fcntl.h>
#include <mutex>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

#include "preview/preview_state.h"
#include "util/error.h"

namespace clrt {

namespace {

enum TevPacket : uint8_t { kCreateImage = 4, kUpdateImageV3 = 6 };

void putU8(std::string& s, uint8_t v) { s.push_back(char(v)); }
template <class T> void putLE(std::string& s, T v) {
    for (size_t i = 0; i < sizeof(T); ++i) s.push_back(char((uint64_t(v) >> (8 * i)) & 0xff));
}
void putFloat(std::string& s, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    putLE<uint32_t>(s, u);
}
void putString(std::string& s, const std::string& v) {
    s.append(v.c_str());  // up to a NUL inside: tev reads NUL-terminated strings
    s.push_back('\0');
}
// Starts a packet: 4 bytes of length (patched by finish) and the type.
std::string begin(uint8_t type) {
    std::string s(4, '\0');
    putU8(s, type);
    return s;
}
std::string finish(std::string s) {
    const uint32_t n = uint32_t(s.size());
    for (int i = 0; i < 4; ++i) s[size_t(i)] = char((n >> (8 * i)) & 0xff);
    return s;
}

// A TCP connection to host:port within timeoutMs; -1 and `why` on failure.
int connectTo(const std::string& host, const std::string& port, int timeoutMs, std::string& why) {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* res = nullptr;
    if (int e = getaddrinfo(host.c_str(), port.c_str(), &hints, &res)) {
        why = gai_strerror(e);
        return -1;
    }
    int fd = -1;
    for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
        fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
        if (fd < 0) continue;
        int rc = connect(fd, a->ai_addr, a->ai_addrlen);
        if (rc != 0 && errno == EINPROGRESS) {
            pollfd p{fd, POLLOUT, 0};
            int err = 0;
            socklen_t len = sizeof err;
            rc = poll(&p, 1, timeoutMs) == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 && err == 0 ? 0 : -1;
            errno = err ? err : ETIMEDOUT;
        }
        if (rc != 0) {
            why = std::strerror(errno);
            close(fd);
            fd = -1;
        }
    }
    freeaddrinfo(res);
    if (fd >= 0) fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    return fd;
}

}  // namespace

std::string tevCreateImagePacket(const std::string& name, int width, int height, const std::vector<std::string>& channels,
                                 bool grabFocus) {
    std::string s = begin(kCreateImage);
    putU8(s, grabFocus ? 1 : 0);
    putString(s, name);
    putLE<int32_t>(s, width);
    putLE<int32_t>(s, height);
    putLE<int32_t>(s, int32_t(channels.size()));
    for (const std::string& c : channels) putString(s, c);
    return finish(std::move(s));
}

std::vector<std::string> tevUpdateImagePackets(const std::string& name, const ImageRGB& img, int tile) {
    std::vector<std::string> out;
    const char* channels[3] = {"R", "G", "B"};
    for (int y0 = 0; y0 < img.height; y0 += tile)
        for (int x0 = 0; x0 < img.width; x0 += tile) {
            const int w = std::min(tile, img.width - x0), h = std::min(tile, img.height - y0);
            std::string s = begin(kUpdateImageV3);
            putU8(s, 0);  // grab focus
            putString(s, name);
            putLE<int32_t>(s, 3);
            for (const char* c : channels) putString(s, c);
            putLE<int32_t>(s, x0);
            putLE<int32_t>(s, y0);
            putLE<int32_t>(s, w);
            putLE<int32_t>(s, h);
            for (int64_t c = 0; c < 3; ++c) putLE<int64_t>(s, c);  // channel offsets: interleaved RGB
            for (int c = 0; c < 3; ++c) putLE<int64_t>(s, 3);      // channel strides
            s.reserve(s.size() + size_t(w) * size_t(h) * 12);
            for (int y = y0; y < y0 + h; ++y)
                for (int x = x0; x < x0 + w; ++x)
                    for (int c = 0; c < 3; ++c) putFloat(s, img.at(x, y, c));
            out.push_back(finish(std::move(s)));
        }
    return out;
}

struct TevClient::Impl {
    int fd = -1;
    std::string where;
    std::mutex mu;
    std::condition_variable cv;
    struct Job {
        std::string name;
        int width = 0, height = 0;  // a CreateImage when img is null
        std::shared_ptr<const ImageRGB> img;
    };
    std::deque<Job> jobs;
    bool closing = false, failed = false;
    std::function<void(double)> onCost;
    std::thread thread;

    bool sendAll(const std::string& bytes) {
        size_t off = 0;
        while (off < bytes.size()) {
            const ssize_t n = ::send(fd, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
            if (n <= 0 && errno == EINTR) continue;
            if (n <= 0) return false;
            off += size_t(n);
        }
        return true;
    }
    void run() {
        for (;;) {
            Job job;
            {
                std::unique_lock<std::mutex> lk(mu);
                cv.wait(lk, [&] { return !jobs.empty() || closing; });
                if (jobs.empty()) return;
                job = std::move(jobs.front());
                jobs.pop_front();
            }
            bool ok = true;
            const double t0 = threadCpuSeconds();
            if (!job.img) ok = sendAll(tevCreateImagePacket(job.name, job.width, job.height, {"R", "G", "B"}));
            else
                for (const std::string& p : tevUpdateImagePackets(job.name, *job.img))
                    if (!(ok = sendAll(p))) break;
            if (onCost) onCost(threadCpuSeconds() - t0);
            if (!ok) {
                warn("--display-server " + where + ": connection lost (" + std::strerror(errno) + "); no more images sent");
                std::lock_guard<std::mutex> lk(mu);
                failed = true;
                jobs.clear();
                return;
            }
        }
    }
    void push(Job j) {
        std::lock_guard<std::mutex> lk(mu);
        if (fd < 0 || failed) return;
        if (j.img)  // a newer image of the same name replaces one still waiting
            for (Job& q : jobs)
                if (q.img && q.name == j.name) {
                    q.img = std::move(j.img);
                    return;
                }
        jobs.push_back(std::move(j));
        cv.notify_one();
    }
};

TevClient::TevClient(const std::string& hostPort, std::function<void(double)> onCost) : impl_(std::make_unique<Impl>()) {
    impl_->onCost = std::move(onCost);
    const size_t colon = hostPort.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == hostPort.size())
        throw Error("--display-server: expected HOST:PORT, got '" + hostPort + "'", ExitCode::Usage);
    std::string host = hostPort.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    impl_->where = hostPort;
    std::string why;
    impl_->fd = connectTo(host, hostPort.substr(colon + 1), 2000, why);
    if (impl_->fd < 0) {
        warn("--display-server " + hostPort + ": cannot connect (" + why + "; is tev running?); rendering without it");
        return;
    }
    timeval tv{5, 0};  // a tev that stops reading: a send gives up after 5 s (then: connection lost)
    setsockopt(impl_->fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    impl_->thread = std::thread([this] {
        sigset_t set;
        sigemptyset(&set);
        sigaddset(&set, SIGPIPE);
        pthread_sigmask(SIG_BLOCK, &set, nullptr);
        impl_->run();
    });
}

TevClient::~TevClient() {
    if (impl_->thread.joinable()) {
        {
            std::lock_guard<std::mutex> lk(impl_->mu);
            impl_->closing = true;
        }
        impl_->cv.notify_all();
        impl_->thread.join();
    }
    if (impl_->fd >= 0) close(impl_->fd);
}

bool TevClient::connected() const {
    std::lock_guard<std::mutex> lk(impl_->mu);
    return impl_->fd >= 0 && !impl_->failed;
}

void TevClient::createImage(const std::string& name, int width, int height) { impl_->push({name, width, height, nullptr}); }

void TevClient::updateImage(const std::string& name, std::shared_ptr<const ImageRGB> img) {
    if (img) impl_->push({name, 0, 0, std::move(img)});
}

}  // namespace clrt
