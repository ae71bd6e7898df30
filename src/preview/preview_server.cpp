// preview_server.cpp — the preview's HTTP server (see preview_server.h): token check, routes, the
// bounded connection queue, and the cache of encoded images (one encode at a time, shared by every
// viewer). Reads the cameras' views from PreviewState and their course references (read-only).
#include "preview/preview_server.h"

#include <arpa/inet.h>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <pthread.h>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fcntl.h>
#include <list>
#include <map>
#include <thread>
#include <unistd.h>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "image/image.h"
#include "image/tonemap.h"
#include "preview/page_assets.h"
#include "preview/preview_images.h"
#include "util/error.h"

namespace clrt {

namespace {

constexpr size_t kWorkers = 16;        // connections served at once
constexpr size_t kWaiting = 64;        // accepted connections waiting for a worker
constexpr size_t kMaxBody = 64;        // request bodies (Stop has none)
constexpr int kThumbWidth = 160;
constexpr size_t kCacheEntries = 24;   // encoded images kept

// httplib's task queue with a bound: enqueue (the accept loop) waits while kWaiting connections
// already wait, so a flood of connections queues in the kernel's backlog, not in memory.
class BoundedQueue : public httplib::TaskQueue {
public:
    BoundedQueue() {
        for (size_t i = 0; i < kWorkers; ++i) threads_.emplace_back([this] { work(); });
    }
    void enqueue(std::function<void()> fn) override {
        std::unique_lock<std::mutex> lk(mu_);
        notFull_.wait(lk, [&] { return jobs_.size() < kWaiting || down_; });
        jobs_.push_back(std::move(fn));
        notEmpty_.notify_one();
    }
    void shutdown() override {
        {
            std::lock_guard<std::mutex> lk(mu_);
            down_ = true;
        }
        notEmpty_.notify_all();
        notFull_.notify_all();
        for (auto& t : threads_) t.join();
    }

private:
    void work() {
        for (;;) {
            std::function<void()> fn;
            {
                std::unique_lock<std::mutex> lk(mu_);
                notEmpty_.wait(lk, [&] { return !jobs_.empty() || down_; });
                if (jobs_.empty()) return;  // down and drained
                fn = std::move(jobs_.front());
                jobs_.pop_front();
                notFull_.notify_one();
            }
            fn();
        }
    }
    std::mutex mu_;
    std::condition_variable notEmpty_, notFull_;
    std::deque<std::function<void()>> jobs_;
    std::vector<std::thread> threads_;
    bool down_ = false;
};

// SIGPIPE blocked in the calling thread (and the threads it starts): writing to a closed connection
// then fails with EPIPE instead of ending the process (cpp-httplib sends without MSG_NOSIGNAL). Debian's
// cpp-httplib 0.11.4 also sets SIGPIPE to ignored for the whole process when it listens (seen in
// /proc/PID/status); this keeps the server safe without relying on that.
void blockSigpipe() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

bool constantTimeEqual(const std::string& a, const std::string& b) {
    if (a.size() != b.size()) return false;
    unsigned char d = 0;
    for (size_t i = 0; i < a.size(); ++i) d |= (unsigned char)(a[i] ^ b[i]);
    return d == 0;
}

// An integer query parameter in [lo, hi]; false if absent or malformed.
bool intParam(const httplib::Request& req, const char* name, int lo, int hi, int& out) {
    if (!req.has_param(name)) return false;
    const std::string v = req.get_param_value(name);
    if (v.empty() || v.size() > 9) return false;
    char* end = nullptr;
    const long x = std::strtol(v.c_str(), &end, 10);
    if (*end != '\0' || x < lo || x > hi) return false;
    out = int(x);
    return true;
}

bool viewParams(const httplib::Request& req, ViewSettings& v) {
    if (req.has_param("tmo")) v.tmo = req.get_param_value("tmo");
    if (req.has_param("ev")) {
        const std::string s = req.get_param_value("ev");
        char* end = nullptr;
        v.exposure = s.empty() || s.size() > 16 ? NAN : std::strtod(s.c_str(), &end);
        if (end && *end != '\0') v.exposure = NAN;
    }
    if (req.has_param("thumb")) v.maxWidth = kThumbWidth;
    return validViewSettings(v);
}

const char* phaseName(CameraPhase p) {
    return p == CameraPhase::Waiting ? "waiting" : p == CameraPhase::Rendering ? "rendering" : "done";
}

std::string hostForUrl(const std::string& host) {
    return host.find(':') != std::string::npos ? "[" + host + "]" : host;
}

}  // namespace

struct PreviewServer::Impl {
    PreviewState& state;
    std::function<void()> onStop;
    std::string token, host;
    int port = 0;
    httplib::Server server;
    std::thread thread;
    std::atomic<bool> viewerSeen{false}, finalSeen{false};
    std::mutex cacheMu, encodeMu, refMu;
    std::list<std::pair<std::string, std::shared_ptr<const std::string>>> cache;  // most recent first
    std::map<int, std::shared_ptr<const ImageRGB>> references;

    Impl(PreviewState& s, std::function<void()> stop, std::string t)
        : state(s), onStop(std::move(stop)), token(std::move(t)) {}

    std::shared_ptr<const std::string> cached(const std::string& key) {
        std::lock_guard<std::mutex> lk(cacheMu);
        for (auto it = cache.begin(); it != cache.end(); ++it)
            if (it->first == key) {
                cache.splice(cache.begin(), cache, it);
                return cache.front().second;
            }
        return nullptr;
    }
    void remember(const std::string& key, std::shared_ptr<const std::string> bytes) {
        std::lock_guard<std::mutex> lk(cacheMu);
        cache.emplace_front(key, std::move(bytes));
        if (cache.size() > kCacheEntries) cache.pop_back();
    }
    std::shared_ptr<const ImageRGB> reference(int cam, const std::string& path) {
        std::lock_guard<std::mutex> lk(refMu);
        auto it = references.find(cam);
        if (it != references.end()) return it->second;
        std::shared_ptr<const ImageRGB> img;
        try {
            img = std::make_shared<const ImageRGB>(readImage(path));
        } catch (const std::exception&) {
        }
        references[cam] = img;
        return img;
    }

    void routes();
    void statusJson(httplib::Response& res);
    void imagePng(const httplib::Request& req, httplib::Response& res, bool ref);
    void imageExr(const httplib::Request& req, httplib::Response& res);
};

void PreviewServer::Impl::statusJson(httplib::Response& res) {
    using nlohmann::json;
    json cams = json::array();
    for (const CameraView& c : state.cameras()) {
        json tp = json::array();
        for (const auto& d : c.figures.throughput) {
            json dj = json::object();
            dj["device"] = d.first;
            dj["samplesPerSecond"] = d.second;
            tp.push_back(std::move(dj));
        }
        json cj = json::object();
        cj["id"] = c.id;
        cj["imageName"] = c.imageName;
        cj["width"] = c.width;
        cj["height"] = c.height;
        cj["phase"] = phaseName(c.phase);
        cj["version"] = c.version;
        cj["spp"] = c.figures.spp;
        cj["relMse"] = c.figures.relMse;  // NaN -> null
        cj["elapsed"] = c.figures.elapsed;
        cj["timeLeft"] = c.figures.timeLeft;
        cj["fraction"] = c.figures.fraction;
        cj["throughput"] = tp;
        cj["hasImage"] = bool(c.image);
        cj["hasReference"] = !c.referencePath.empty();
        cj["tonemap"] = c.hasTonemap ? tmoKindName(c.tonemap.op) : "linear";
        cams.push_back(std::move(cj));
    }
    const bool finished = state.finished();
    if (finished) finalSeen = true;
    json j = {{"stage", state.stage()}, {"current", state.current()}, {"finished", finished}, {"cameras", cams},
              {"renderThreadSeconds", state.renderThreadSeconds()}, {"serverSeconds", state.serverSeconds()}};
    res.set_content(j.dump(), "application/json");
}

void PreviewServer::Impl::imagePng(const httplib::Request& req, httplib::Response& res, bool ref) {
    int cam = 0;
    ViewSettings v;
    CameraView c;
    if (!intParam(req, "cam", 0, 1 << 20, cam) || !viewParams(req, v)) {
        res.status = 400;
        return;
    }
    if (!state.camera(cam, c) || (ref ? c.referencePath.empty() : !c.image)) {
        res.status = 404;
        return;
    }
    const std::string key = (ref ? "ref/" : "img/") + std::to_string(cam) + "/" + std::to_string(ref ? 0 : c.version) +
                            "/" + v.tmo + "/" + std::to_string(v.exposure) + "/" + std::to_string(v.maxWidth);
    std::shared_ptr<const std::string> png = cached(key);
    if (!png) {
        std::lock_guard<std::mutex> one(encodeMu);  // one encode at a time; the others then find it cached
        png = cached(key);
        if (!png) {
            std::shared_ptr<const ImageRGB> img = ref ? reference(cam, c.referencePath) : c.image;
            if (!img) {
                res.status = 404;
                return;
            }
            const double t0 = threadCpuSeconds();
            const bool ldr = ref ? !img->isHdr : c.ldrOutput;
            int w = 0, h = 0;
            std::vector<unsigned char> rgb = previewView(*img, ldr, c.hasTonemap, c.tonemap, v, w, h);
            png = std::make_shared<const std::string>(encodePng8("preview.png", w, h, rgb));
            remember(key, png);
            state.addServerSeconds(threadCpuSeconds() - t0);
        }
    }
    res.set_content(png->data(), png->size(), "image/png");
}

void PreviewServer::Impl::imageExr(const httplib::Request& req, httplib::Response& res) {
    int cam = 0;
    CameraView c;
    if (!intParam(req, "cam", 0, 1 << 20, cam)) {
        res.status = 400;
        return;
    }
    if (!state.camera(cam, c) || !c.image) {
        res.status = 404;
        return;
    }
    std::string bytes;
    {
        std::lock_guard<std::mutex> one(encodeMu);
        bytes = exrBytes(*c.image, {{"renderer", "clrt (preview)"}, {"spp", std::to_string(c.figures.spp)},
                                    {"partial", c.phase == CameraPhase::Done ? "" : "preview of a render in progress"}});
    }
    std::string stem = c.imageName.substr(0, c.imageName.rfind('.'));
    for (char& ch : stem)
        if (!std::isalnum((unsigned char)ch) && ch != '_' && ch != '-') ch = '_';
    res.set_header("Content-Disposition", "attachment; filename=\"" + stem + "_" + std::to_string(c.figures.spp) + "spp.exr\"");
    res.set_content(std::move(bytes), "image/x-exr");
}

void PreviewServer::Impl::routes() {
    const std::string p = "/" + token;
    server.set_pre_routing_handler([this, p](const httplib::Request& req, httplib::Response& res) {
        const bool ok = req.path.size() >= p.size() && constantTimeEqual(req.path.substr(0, p.size()), p) &&
                        (req.path.size() == p.size() || req.path[p.size()] == '/');
        if (ok) {
            viewerSeen = true;
            return httplib::Server::HandlerResponse::Unhandled;
        }
        res.status = 403;
        res.set_content("403 forbidden: this preview needs the URL with its token, as clrt printed it\n", "text/plain");
        return httplib::Server::HandlerResponse::Handled;
    });
    server.Get(p, [p](const httplib::Request&, httplib::Response& res) { res.set_redirect(p + "/"); });
    server.Get(p + "/", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(previewPageHtml(), "text/html; charset=utf-8");
    });
    server.Get(p + "/page.js", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(previewPageJs(), "text/javascript; charset=utf-8");
    });
    server.Get(p + "/status.json", [this](const httplib::Request&, httplib::Response& res) { statusJson(res); });
    server.Get(p + "/image.png", [this](const httplib::Request& q, httplib::Response& r) { imagePng(q, r, false); });
    server.Get(p + "/reference.png", [this](const httplib::Request& q, httplib::Response& r) { imagePng(q, r, true); });
    server.Get(p + "/image.exr", [this](const httplib::Request& q, httplib::Response& r) { imageExr(q, r); });
    server.Post(p + "/stop", [this](const httplib::Request&, httplib::Response& res) {
        onStop();
        res.set_content("{\"stopping\":true}", "application/json");
    });
    server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
        if (res.body.empty()) res.set_content(std::to_string(res.status) + "\n", "text/plain");
    });
    server.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr) {
        res.status = 500;
        res.set_content("500 internal error\n", "text/plain");
    });
}

PreviewAddress parsePreviewAddress(const std::string& flag, const std::string& spec) {
    PreviewAddress a;
    std::string portText = spec;
    const size_t colon = spec.rfind(':');
    if (colon != std::string::npos) {
        a.host = spec.substr(0, colon);
        portText = spec.substr(colon + 1);
        if (a.host.size() >= 2 && a.host.front() == '[' && a.host.back() == ']') a.host = a.host.substr(1, a.host.size() - 2);
        if (a.host.empty()) throw Error(flag + ": expected [ADDR:]PORT, got '" + spec + "'", ExitCode::Usage);
    }
    char* end = nullptr;
    const long port = std::strtol(portText.c_str(), &end, 10);
    if (portText.empty() || *end != '\0' || port < 0 || port > 65535)
        throw Error(flag + ": expected [ADDR:]PORT with PORT in 0..65535, got '" + spec + "'", ExitCode::Usage);
    a.port = int(port);
    in_addr v4{};
    a.loopback = a.host == "localhost" || a.host == "::1" ||
                 (inet_pton(AF_INET, a.host.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127);
    return a;
}

std::string randomToken() {
    unsigned char b[16];
    const int fd = ::open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    const bool ok = fd >= 0 && ::read(fd, b, sizeof b) == ssize_t(sizeof b);
    if (fd >= 0) ::close(fd);
    if (!ok) throw Error("--preview: cannot read /dev/urandom for the preview's token", ExitCode::Usage);
    std::string t;
    char hex[3];
    for (unsigned char c : b) {
        std::snprintf(hex, sizeof hex, "%02x", c);
        t += hex;
    }
    return t;
}

PreviewServer::PreviewServer(PreviewState& state, std::function<void()> onStop, std::string token)
    : impl_(std::make_unique<Impl>(state, std::move(onStop), std::move(token))) {}

PreviewServer::~PreviewServer() { stop(); }

void PreviewServer::start(const PreviewAddress& addr, const std::string& flag) {
    httplib::Server& s = impl_->server;
    s.new_task_queue = [] { return new BoundedQueue(); };
    s.set_payload_max_length(kMaxBody);
    s.set_read_timeout(5, 0);
    s.set_write_timeout(5, 0);
    s.set_keep_alive_timeout(2);     // an idle keep-alive connection gives its worker back soon
    s.set_keep_alive_max_count(8);   // and so does a busy one, after 8 requests
    s.set_default_headers({{"Cache-Control", "no-store"}, {"X-Content-Type-Options", "nosniff"},
                           {"Referrer-Policy", "no-referrer"}, {"X-Frame-Options", "DENY"},
                           {"Content-Security-Policy", "default-src 'self'; img-src 'self' blob: data:; "
                                                       "style-src 'self' 'unsafe-inline'; frame-ancestors 'none'"}});
    impl_->routes();
    if (addr.host.find(':') != std::string::npos) s.set_address_family(AF_INET6);
    int port = addr.port;
    errno = 0;
    const bool bound = port == 0 ? (port = s.bind_to_any_port(addr.host)) > 0 : s.bind_to_port(addr.host, port);
    if (!bound)
        throw Error(flag + ": cannot listen on " + hostForUrl(addr.host) + ":" + std::to_string(addr.port) +
                        (errno ? std::string(" (") + std::strerror(errno) + ")" : std::string(" (address in use or not local)")),
                    ExitCode::Usage);
    impl_->host = addr.host == "localhost" ? "127.0.0.1" : addr.host;
    impl_->port = port;
    if (!addr.loopback)
        std::fprintf(stderr, "warning: %s: listening on %s, not a loopback address: anyone who can reach it and "
                             "sees the URL's token can watch and stop this render (plain HTTP, no encryption)\n",
                     flag.c_str(), addr.host.c_str());
    impl_->thread = std::thread([this] {
        blockSigpipe();  // a viewer that goes away mid-response: EPIPE in this thread and its workers
        impl_->server.listen_after_bind();
    });
}

int PreviewServer::port() const { return impl_->port; }
const std::string& PreviewServer::token() const { return impl_->token; }
std::string PreviewServer::url() const {
    const std::string host = impl_->host == "0.0.0.0" || impl_->host == "::" ? "127.0.0.1" : impl_->host;
    return "http://" + hostForUrl(host) + ":" + std::to_string(impl_->port) + "/" + impl_->token + "/";
}

void PreviewServer::linger(double seconds) {
    if (!impl_->viewerSeen.load()) return;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!impl_->finalSeen.load() && std::chrono::steady_clock::now() < end)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

void PreviewServer::stop() {
    if (!impl_->thread.joinable()) return;
    impl_->server.stop();
    impl_->thread.join();
}

}  // namespace clrt
