// preview_server.h — `clrt render --preview [ADDR:]PORT`: an HTTP server (cpp-httplib, Debian's
// libcpp-httplib-dev) on threads of its own that serves the embedded page (page.html, page.js) and the
// JSON and image endpoints of a PreviewState, behind a random 128-bit token in the URL path. Nothing
// on the file system is served by request path. Limits: request bodies (64 bytes), headers and URIs
// (cpp-httplib's 8 KiB), 5 s read/write timeouts, 16 worker threads (a connection keeps one for at
// most 8 requests or 2 s idle) and 64 waiting connections (then
// the accept loop waits and the kernel's backlog holds the rest). See docs/preview.md.
#pragma once
#include <functional>
#include <memory>
#include <string>

#include "preview/preview_state.h"

namespace clrt {

struct PreviewAddress {
    std::string host = "127.0.0.1";
    int port = 0;
    bool loopback = true;  // host is 127.0.0.0/8, ::1 or localhost
};

// "[ADDR:]PORT" (PORT 0: any free port; [v6]:PORT for IPv6); throws clrt::Error (Usage) naming `flag`.
PreviewAddress parsePreviewAddress(const std::string& flag, const std::string& spec);

// 32 hex digits from /dev/urandom (throws clrt::Error when it cannot be read).
std::string randomToken();

class PreviewServer {
public:
    // onStop: what the page's Stop button does (clrt render: raise SIGINT, exactly as Ctrl-C).
    PreviewServer(PreviewState& state, std::function<void()> onStop, std::string token = randomToken());
    ~PreviewServer();  // stops the server and joins its threads
    PreviewServer(const PreviewServer&) = delete;
    PreviewServer& operator=(const PreviewServer&) = delete;

    // Binds and starts serving; throws clrt::Error (Usage, exit 1) with one line when the address
    // cannot be bound (a port in use). Warns when the address is not a loopback one.
    void start(const PreviewAddress& addr, const std::string& flag = "--preview");
    int port() const;
    std::string url() const;  // http://HOST:PORT/TOKEN/
    const std::string& token() const;
    // After the render: serves until a page has fetched the final status (at most `seconds`; not at
    // all when no page ever connected).
    void linger(double seconds);
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace clrt
