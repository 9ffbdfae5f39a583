// What connects the server (server.h) to what a page shows: the viewer of a scene (viewer.h) or the live
// training page (training_monitor.h). Plain C++, no Boost: the server includes Beast, these do not.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "serve/protocol.h"

namespace npt::serve {

// Where a worker's output goes. Called from the worker thread; must not block.
class ViewerSink {
  public:
    virtual ~ViewerSink() = default;
    // A binary frame for every client: [u32 little-endian n][n bytes of JSON header][JPEG].
    virtual void broadcast_frame(std::shared_ptr<const std::string> frame) = 0;
    // The same for one client: a page's own view. Only the newest frame waits for a slow page.
    virtual void send_frame(uint64_t client, std::shared_ptr<const std::string> frame) = 0;
    // A JSON text message for one client (`client` != 0) or every client (0).
    virtual void send_text(uint64_t client, std::shared_ptr<const std::string> text) = 0;
};

// Where the pages' messages go. Called from the server's thread; must not block.
class PageHandler {
  public:
    virtual ~PageHandler() = default;
    // The state a newly connected page starts from (JSON text: {"type": "state", ...}).
    virtual std::shared_ptr<const std::string> state() const = 0;
    // A parsed message from page `client`, queued for the worker.
    virtual void post(uint64_t client, ClientMessage message) = 0;
    // A page connected (before any of its messages) or closed (after its last): a handler that keeps a view
    // per page makes or frees it.
    virtual void page_opened(uint64_t client) { (void)client; }
    virtual void page_closed(uint64_t client) { (void)client; }
};

// A response the server gives beside its embedded assets: a document made in memory, or a file on disk
// (served with HTTP Range requests, for a video). Only what a RouteSource lists is served: no URL becomes a
// path.
struct ServedFile {
    std::string content_type;
    std::string body;            // when `file` is empty
    std::filesystem::path file;  // else: this file, read when it is requested
};

// Extra URL paths the server answers (the capture report, serve/capture_report.h). Called on the server's
// thread; must not block for long. `path` is percent-decoded, without the query.
class RouteSource {
  public:
    virtual ~RouteSource() = default;
    virtual std::optional<ServedFile> find(std::string_view path) const = 0;
};

}  // namespace npt::serve
