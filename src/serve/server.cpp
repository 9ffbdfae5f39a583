#include "serve/server.h"

#include <spdlog/spdlog.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "core/error.h"
#include "serve/assets.h"
#include "serve/http_util.h"
#include "serve/protocol.h"

namespace npt::serve {
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

std::string random_token() {
    std::random_device rd;  // /dev/urandom on Linux
    std::string hex;
    for (int i = 0; i < 4; ++i) {
        const uint32_t v = rd();
        static const char* digits = "0123456789abcdef";
        for (int k = 7; k >= 0; --k) hex += digits[(v >> (4 * k)) & 15];
    }
    return hex;
}

bool is_loopback_host(const std::string& host) {
    if (host == "localhost") return true;
    boost::system::error_code ec;
    const asio::ip::address a = asio::ip::make_address(host, ec);
    return !ec && a.is_loopback();
}

namespace {

constexpr size_t k_max_texts_queued = 256;  // per page; beyond it the oldest text is dropped
constexpr std::chrono::seconds k_http_timeout{30};
// A file's response holds at most this much: an open-ended Range ("bytes=0-", a video) gets this part, and
// the browser asks for the rest; a request without Range for a larger file is refused.
constexpr uint64_t k_max_range_bytes = uint64_t(4) << 20;
constexpr uint64_t k_max_whole_bytes = uint64_t(256) << 20;

// An open file descriptor, closed on scope exit.
struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

// Reads [first, first + n) of an open file; false on a short read (the file shrank) or an error.
bool read_part(int fd, uint64_t first, uint64_t n, std::string* out) {
    out->resize(size_t(n));
    uint64_t done = 0;
    while (done < n) {
        const ssize_t r = ::pread(fd, out->data() + done, size_t(n - done), off_t(first + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        done += uint64_t(r);
    }
    return true;
}

std::string query_value(std::string_view target, std::string_view key) {
    const size_t q = target.find('?');
    if (q == std::string_view::npos) return {};
    std::string_view rest = target.substr(q + 1);
    while (!rest.empty()) {
        const size_t amp = rest.find('&');
        const std::string_view kv = rest.substr(0, amp);
        const size_t eq = kv.find('=');
        if (eq != std::string_view::npos && kv.substr(0, eq) == key) return std::string(kv.substr(eq + 1));
        if (amp == std::string_view::npos) break;
        rest = rest.substr(amp + 1);
    }
    return {};
}

std::string cookie_value(std::string_view cookies, std::string_view key) {
    while (!cookies.empty()) {
        const size_t semi = cookies.find(';');
        std::string_view kv = cookies.substr(0, semi);
        while (!kv.empty() && kv.front() == ' ') kv.remove_prefix(1);
        const size_t eq = kv.find('=');
        if (eq != std::string_view::npos && kv.substr(0, eq) == key) return std::string(kv.substr(eq + 1));
        if (semi == std::string_view::npos) break;
        cookies = cookies.substr(semi + 1);
    }
    return {};
}

// Constant time in the token's length: a timing side channel should not reveal it a byte at a time.
bool same_token(const std::string& a, const std::string& b) {
    if (a.size() != b.size()) return false;
    unsigned char d = 0;
    for (size_t i = 0; i < a.size(); ++i) d |= static_cast<unsigned char>(a[i] ^ b[i]);
    return d == 0;
}

}  // namespace

struct Server::Impl {
    // Declared before the io_context: destroying it destroys the sessions its pending handlers hold.
    struct WsSession;
    std::map<uint64_t, std::weak_ptr<WsSession>> sessions;  // io thread only
    std::atomic<size_t> session_count{0};
    ServerOptions options;
    asio::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    PageHandler* viewer = nullptr;
    uint16_t port = 0;
    uint64_t next_id = 1;

    // Host header check (DNS rebinding: a web page of another site resolving its name to 127.0.0.1).
    bool host_ok(std::string_view host) const {
        if (!is_loopback_host(options.host) || !options.token.empty()) return true;
        const std::string p = ":" + std::to_string(port);
        for (const char* h : {"127.0.0.1", "localhost", "[::1]"})
            if (host == std::string(h) + p || host == std::string(h)) return true;
        return false;
    }
    bool token_ok(const http::request<http::string_body>& req) const {
        if (options.token.empty()) return true;
        const std::string_view target(req.target().data(), req.target().size());
        if (same_token(query_value(target, "token"), options.token)) return true;
        const auto c = req.find(http::field::cookie);
        return c != req.end() &&
               same_token(cookie_value(std::string_view(c->value().data(), c->value().size()), "nerfpt_token"),
                          options.token);
    }

    struct WsSession : std::enable_shared_from_this<WsSession> {
        Impl& server;
        uint64_t id;
        websocket::stream<beast::tcp_stream> ws;
        beast::flat_buffer buffer;
        std::deque<std::shared_ptr<const std::string>> texts;
        std::shared_ptr<const std::string> frame;  // only the newest frame waits: a slow page skips frames
        std::shared_ptr<const std::string> writing;
        bool open = false;

        WsSession(Impl& s, uint64_t i, tcp::socket&& socket) : server(s), id(i), ws(std::move(socket)) {}
        ~WsSession() { --server.session_count; }

        void start(http::request<http::string_body> req) {
            ++server.session_count;
            ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
            ws.read_message_max(k_max_message_bytes);
            beast::get_lowest_layer(ws).expires_never();
            ws.async_accept(req, [self = shared_from_this()](beast::error_code ec) {
                if (ec) {
                    spdlog::warn("serve: WebSocket handshake failed: {}", ec.message());
                    return;
                }
                self->open = true;
                self->server.sessions[self->id] = self;
                spdlog::info("serve: page {} connected ({} open)", self->id, self->server.session_count.load());
                if (self->server.viewer) {
                    self->server.viewer->page_opened(self->id);
                    self->queue_text(self->server.viewer->state());
                }
                self->read();
            });
        }
        void read() {
            ws.async_read(buffer, [self = shared_from_this()](beast::error_code ec, size_t) {
                if (ec) {
                    if (ec != websocket::error::closed && ec != asio::error::operation_aborted && ec != asio::error::eof)
                        spdlog::warn("serve: page {}: {}{}; closing it", self->id, ec.message(),
                                     self->close_received());
                    self->close();
                    return;
                }
                self->on_message();
                self->read();
            });
        }
        // Beast reports how its closing handshake ended, not the page's Close frame before it: a browser that
        // sent Close and dropped the connection at once reads as "Transport endpoint is not connected" (or a
        // reset). Chromium does so with code 1001 when the page unloads or its renderer dies, and with 1002
        // when it fails the WebSocket (a frame it refuses): the code tells them apart.
        std::string close_received() const {
            const websocket::close_reason& r = ws.reason();
            if (r.code == websocket::close_code::none) return {};
            return " (after the page's Close frame, code " + std::to_string(r.code) +
                   (r.reason.empty() ? "" : " '" + std::string(r.reason.data(), r.reason.size()) + "'") + ")";
        }
        void on_message() {
            const std::string text = beast::buffers_to_string(buffer.data());
            buffer.consume(buffer.size());
            if (!ws.got_text()) {
                error("message: expected JSON text, got a binary message");
                return;
            }
            try {
                ClientMessage m = parse_client_message(text);
                if (server.viewer) server.viewer->post(id, std::move(m));
            } catch (const Error& e) {
                error(e.what());
            }
        }
        void error(const std::string& what) {
            spdlog::warn("serve: page {}: {}", id, what);
            nlohmann::json j = {{"type", "error"}, {"message", what}};
            queue_text(std::make_shared<const std::string>(j.dump()));
        }
        void close() {
            if (!open) return;
            open = false;
            server.sessions.erase(id);
            texts.clear();
            frame.reset();
            if (server.viewer) server.viewer->page_closed(id);
            spdlog::info("serve: page {} closed", id);
        }
        void queue_text(std::shared_ptr<const std::string> t) {
            if (!open || !t) return;
            if (texts.size() >= k_max_texts_queued) texts.pop_front();
            texts.push_back(std::move(t));
            write();
        }
        void queue_frame(std::shared_ptr<const std::string> f) {
            if (!open) return;
            frame = std::move(f);
            write();
        }
        void write() {
            if (writing || !open) return;
            bool text = false;
            if (!texts.empty()) {
                writing = texts.front();
                texts.pop_front();
                text = true;
            } else if (frame) {
                writing = std::move(frame);
                frame.reset();
            } else {
                return;
            }
            ws.text(text);
            ws.async_write(asio::buffer(*writing), [self = shared_from_this()](beast::error_code ec, size_t) {
                self->writing.reset();
                if (ec) {
                    if (ec != asio::error::operation_aborted && ec != websocket::error::closed)
                        spdlog::warn("serve: page {}: sending failed: {}; closing it", self->id,
                                     ec.message());
                    self->close();
                    return;
                }
                self->write();
            });
        }
    };

    struct HttpSession : std::enable_shared_from_this<HttpSession> {
        Impl& server;
        beast::tcp_stream stream;
        beast::flat_buffer buffer;
        std::optional<http::request_parser<http::string_body>> parser;

        HttpSession(Impl& s, tcp::socket&& socket) : server(s), stream(std::move(socket)) {}

        void read() {
            parser.emplace();
            parser->header_limit(16 * 1024);
            parser->body_limit(16 * 1024);
            stream.expires_after(k_http_timeout);
            http::async_read(stream, buffer, *parser, [self = shared_from_this()](beast::error_code ec, size_t) {
                if (ec) {
                    if (ec != http::error::end_of_stream && ec != asio::error::operation_aborted &&
                        ec != beast::error::timeout)
                        spdlog::debug("serve: HTTP request refused: {}", ec.message());
                    beast::error_code ignored;
                    self->stream.socket().shutdown(tcp::socket::shutdown_send, ignored);
                    return;
                }
                self->handle(self->parser->release());
            });
        }

        using Headers = std::vector<std::pair<http::field, std::string>>;
        void respond(http::status status, std::string_view type, std::string body, bool keep_alive,
                     const std::string& cookie = {}, bool head = false, const Headers& headers = {},
                     std::optional<uint64_t> head_length = std::nullopt) {
            auto res = std::make_shared<http::response<http::string_body>>(status, 11);
            res->set(http::field::server, "nerfpt");
            res->set(http::field::content_type, std::string(type));
            res->set(http::field::cache_control, "no-store");
            res->set("X-Content-Type-Options", "nosniff");
            if (!cookie.empty()) res->set(http::field::set_cookie, cookie);
            for (const auto& [field, value] : headers) res->set(field, value);
            res->keep_alive(keep_alive);
            const uint64_t size = head && head_length ? *head_length : body.size();
            if (!head) res->body() = std::move(body);
            res->content_length(size);
            http::async_write(stream, *res, [self = shared_from_this(), res](beast::error_code ec, size_t) {
                if (ec || !res->keep_alive()) {
                    beast::error_code ignored;
                    self->stream.socket().shutdown(tcp::socket::shutdown_send, ignored);
                    return;
                }
                self->read();
            });
        }

        void handle(http::request<http::string_body> req) {
            const std::string_view host(req[http::field::host].data(), req[http::field::host].size());
            if (!server.host_ok(host)) {
                spdlog::warn("serve: refused a request for host '{}'", std::string(host));
                return respond(http::status::forbidden, "text/plain", "forbidden host\n", false);
            }
            if (!server.token_ok(req)) {
                spdlog::warn("serve: refused a request without the right token");
                return respond(http::status::forbidden, "text/plain",
                               "this nerfpt serve needs the token printed at its start: open the URL it printed\n",
                               false);
            }
            std::string target(req.target().data(), req.target().size());
            std::string path = target.substr(0, target.find('?'));
            if (websocket::is_upgrade(req)) {
                if (path != "/ws") return respond(http::status::not_found, "text/plain", "not found\n", false);
                // A page of another origin must not drive the viewer (cross-site WebSocket hijacking).
                const auto origin = req.find(http::field::origin);
                if (origin != req.end()) {
                    const std::string o(origin->value().data(), origin->value().size());
                    if (o != "http://" + std::string(host) && o != "https://" + std::string(host)) {
                        spdlog::warn("serve: refused a WebSocket from origin '{}'", o);
                        return respond(http::status::forbidden, "text/plain", "forbidden origin\n", false);
                    }
                }
                stream.expires_never();
                auto ws = std::make_shared<WsSession>(server, server.next_id++, stream.release_socket());
                ws->start(std::move(req));
                return;
            }
            if (req.method() != http::verb::get && req.method() != http::verb::head)
                return respond(http::status::method_not_allowed, "text/plain", "GET only\n", req.keep_alive());
            if (path == "/") path = server.options.index;
            std::string cookie;
            if (!server.options.token.empty())
                cookie = "nerfpt_token=" + server.options.token + "; HttpOnly; SameSite=Strict; Path=/";
            const bool head = req.method() == http::verb::head;
            if (const Asset* a = find_asset(path))
                return respond(http::status::ok, a->content_type,
                               std::string(reinterpret_cast<const char*>(a->data), a->size), req.keep_alive(),
                               cookie, head);
            // The routes' own list decides; the decoded path is only compared with it.
            if (server.options.routes)
                if (const auto decoded = percent_decode_path(path))
                    if (auto found = server.options.routes->find(*decoded)) {
                        if (found->file.empty())
                            return respond(http::status::ok, found->content_type, std::move(found->body),
                                           req.keep_alive(), cookie, head);
                        return serve_file(*found, req, cookie, head);
                    }
            respond(http::status::not_found, "text/plain", "not found\n", req.keep_alive());
        }

        // A listed file, with a single byte range when asked (a <video> seeks with them). Opened without
        // following a symbolic link: one put in its place after the listing is not followed out of the
        // folder.
        void serve_file(const ServedFile& f, const http::request<http::string_body>& req,
                        const std::string& cookie, bool head) {
            Fd fd{::open(f.file.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC)};
            struct stat st {};
            if (fd.fd < 0 || ::fstat(fd.fd, &st) != 0 || !S_ISREG(st.st_mode)) {
                spdlog::warn("serve: {}: cannot open it ({})", f.file.string(),
                             fd.fd < 0 ? std::strerror(errno) : "not a file");
                return respond(http::status::not_found, "text/plain", "not found\n", req.keep_alive());
            }
            const uint64_t size = uint64_t(st.st_size);
            const auto range_header = req.find(http::field::range);
            const ByteRange range = range_header == req.end()
                                        ? ByteRange{}
                                        : parse_byte_range(std::string_view(range_header->value().data(),
                                                                            range_header->value().size()),
                                                           size, k_max_range_bytes);
            Headers headers{{http::field::accept_ranges, "bytes"}};
            if (range.kind == ByteRange::Kind::unsatisfiable) {
                headers.push_back({http::field::content_range, "bytes */" + std::to_string(size)});
                return respond(http::status::range_not_satisfiable, "text/plain", "range not satisfiable\n",
                               req.keep_alive(), cookie, head, headers);
            }
            uint64_t first = 0, n = size;
            http::status status = http::status::ok;
            if (range.kind == ByteRange::Kind::partial) {
                first = range.first;
                n = range.last - range.first + 1;
                status = http::status::partial_content;
                headers.push_back({http::field::content_range, "bytes " + std::to_string(range.first) + "-" +
                                                                   std::to_string(range.last) + "/" +
                                                                   std::to_string(size)});
            } else if (size > k_max_whole_bytes) {
                return respond(http::status::payload_too_large, "text/plain",
                               "too large to send whole: ask for byte ranges\n", req.keep_alive());
            }
            std::string body;
            if (!head && !read_part(fd.fd, first, n, &body)) {
                spdlog::warn("serve: {}: cannot read it", f.file.string());
                return respond(http::status::internal_server_error, "text/plain", "cannot read the file\n",
                               false);
            }
            respond(status, f.content_type, std::move(body), req.keep_alive(), cookie, head, headers, n);
        }
    };

    void accept() {
        acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
            if (ec) {
                if (ec == asio::error::operation_aborted) return;
                spdlog::warn("serve: accept failed: {}", ec.message());
            } else {
                // Frames go out as soon as they are written: with Nagle's algorithm a frame's last small segment
                // waits for the page's (delayed, up to 40 ms) acknowledgement of the one before.
                beast::error_code nodelay_ec;
                socket.set_option(tcp::no_delay(true), nodelay_ec);
                std::make_shared<HttpSession>(*this, std::move(socket))->read();
            }
            accept();
        });
    }
};

Server::Server(const ServerOptions& options) : m(std::make_unique<Impl>()) {
    m->options = options;
    boost::system::error_code ec;
    const std::string host = options.host == "localhost" ? "127.0.0.1" : options.host;
    const asio::ip::address address = asio::ip::make_address(host, ec);
    if (ec) throw Error("--host: '" + options.host + "' is not an IP address (" + ec.message() + ")");
    const tcp::endpoint ep(address, options.port);
    m->acceptor.open(ep.protocol(), ec);
    if (!ec) m->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) m->acceptor.bind(ep, ec);
    if (!ec) m->acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (ec)
        throw Error("cannot listen on " + options.host + ":" + std::to_string(options.port) + ": " + ec.message() +
                    (ec == asio::error::address_in_use ? " (another program uses the port: pick one with --port)" : ""));
    m->port = m->acceptor.local_endpoint().port();
    m->accept();
}

Server::~Server() { stop(); }

void Server::attach(PageHandler* handler) { m->viewer = handler; }
uint16_t Server::port() const { return m->port; }
size_t Server::sessions() const { return m->session_count.load(); }

std::string Server::url() const {
    std::string host = m->options.host;
    if (host == "0.0.0.0") host = "127.0.0.1";  // reachable from here; other machines use this one's address
    if (host.find(':') != std::string::npos) host = "[" + host + "]";
    std::string u = "http://" + host + ":" + std::to_string(m->port) + "/";
    if (!m->options.token.empty()) u += "?token=" + m->options.token;
    return u;
}

void Server::run() { m->ioc.run(); }

void Server::stop() {
    asio::post(m->ioc, [impl = m.get()] {
        boost::system::error_code ec;
        impl->acceptor.close(ec);
        impl->ioc.stop();
    });
}

void Server::broadcast_frame(std::shared_ptr<const std::string> frame) {
    asio::post(m->ioc, [impl = m.get(), frame] {
        for (auto& [id, w] : impl->sessions)
            if (auto s = w.lock()) s->queue_frame(frame);
    });
}

void Server::send_frame(uint64_t client, std::shared_ptr<const std::string> frame) {
    asio::post(m->ioc, [impl = m.get(), client, frame] {
        const auto it = impl->sessions.find(client);
        if (it != impl->sessions.end())
            if (auto s = it->second.lock()) s->queue_frame(frame);
    });
}

void Server::send_text(uint64_t client, std::shared_ptr<const std::string> text) {
    asio::post(m->ioc, [impl = m.get(), client, text] {
        for (auto& [id, w] : impl->sessions)
            if (client == 0 || id == client)
                if (auto s = w.lock()) s->queue_text(text);
    });
}

}  // namespace npt::serve
