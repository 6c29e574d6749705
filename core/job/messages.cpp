// The job's messages and their codec (messages.hpp).
#include "messages.hpp"

#include <string_view>

#include "byte_buffer.hpp"
#include "piece_bytes.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Reserving a message's pieces' bytes (detail::piece_byte_size) before
// putting them keeps a large message from growing by doubling, which on the
// root seam's worker held up to twice the surface's size at once.
class Writer : public detail::ByteWriter<MessageBytes> {
public:
    void reserve(std::size_t more) { bytes.reserve(bytes.size() + more); }
};

class Reader : public detail::ByteReader {
public:
    explicit Reader(const MessageBytes& bytes)
        : ByteReader(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                     [](const char*) { throw Error("truncated message between MPI ranks"); }) {}
};

void put_string(Writer& out, const std::string& text) { out.put_array(std::vector<char>(text.begin(), text.end())); }

std::string get_string(Reader& in) {
    const auto chars = in.get_array<char>();
    return std::string(chars.begin(), chars.end());
}

MessageBytes cores_only(const MessageBytes& cores) {
    Writer out;
    out.put_array(cores);
    return std::move(out.bytes);
}

} // namespace

MessageBytes encode(const ReadyMessage& message) { return cores_only(message.cores); }

ReadyMessage decode_ready(const MessageBytes& bytes) {
    Reader in(bytes);
    return ReadyMessage{in.get_array<std::byte>()};
}

MessageBytes encode(const LendMessage& message) { return cores_only(message.cores); }

LendMessage decode_lend(const MessageBytes& bytes) {
    Reader in(bytes);
    return LendMessage{in.get_array<std::byte>()};
}

MessageBytes encode(const TaskMessage& message) {
    Writer out;
    out.put(message.task);
    out.put(message.gpu);
    const bool seam = message.left && message.right;
    out.put<std::int32_t>(seam ? 2 : 0);
    if (seam) {
        out.reserve(detail::piece_byte_size(*message.left) + detail::piece_byte_size(*message.right));
        detail::put_piece(out, *message.left);
        detail::put_piece(out, *message.right);
    }
    return std::move(out.bytes);
}

TaskMessage decode_task(const MessageBytes& bytes) {
    Reader in(bytes);
    TaskMessage message;
    message.task = in.get<std::int32_t>();
    message.gpu = in.get<std::int32_t>();
    if (in.get<std::int32_t>() == 2) {
        message.left = detail::get_piece(in);
        message.right = detail::get_piece(in);
    }
    return message;
}

namespace {

void put_result(Writer& out, const ResultMessage& message) {
    const TaskRecord& r = message.record;
    out.put(r.task);
    out.put(message.seconds);
    out.put(r.threads);
    out.put(r.triangles_in);
    out.put(r.triangles_out);
    out.put(r.samples_out);
    out.put(r.stages);
    out.put(r.field_low);
    out.put(r.field_high);
    out.reserve(detail::piece_byte_size(message.piece));
    detail::put_piece(out, message.piece);
}

ResultMessage get_result(Reader& in) {
    ResultMessage message;
    TaskRecord& r = message.record;
    r.task = in.get<std::int32_t>();
    message.seconds = in.get<double>();
    r.threads = in.get<std::int32_t>();
    r.triangles_in = in.get<std::uint64_t>();
    r.triangles_out = in.get<std::uint64_t>();
    r.samples_out = in.get<std::uint64_t>();
    r.stages = in.get<TaskRecord::Stages>();
    r.field_low = in.get<float>();
    r.field_high = in.get<float>();
    message.piece = detail::get_piece(in);
    return message;
}

} // namespace

MessageBytes encode(const ResultMessage& message) {
    Writer out;
    put_result(out, message);
    return std::move(out.bytes);
}

ResultMessage decode_result(const MessageBytes& bytes) {
    Reader in(bytes);
    return get_result(in);
}

MessageBytes encode(const BatchMessage& message) {
    Writer out;
    out.put(message.gpu);
    out.put_array(message.tasks);
    return std::move(out.bytes);
}

BatchMessage decode_batch(const MessageBytes& bytes) {
    Reader in(bytes);
    BatchMessage message;
    message.gpu = in.get<std::int32_t>();
    message.tasks = in.get_array<std::int32_t>();
    return message;
}

MessageBytes encode(const BatchResultMessage& message) {
    Writer out;
    out.put(static_cast<std::uint64_t>(message.results.size()));
    for (const ResultMessage& result : message.results) put_result(out, result);
    return std::move(out.bytes);
}

BatchResultMessage decode_batch_result(const MessageBytes& bytes) {
    Reader in(bytes);
    BatchResultMessage message;
    const auto count = in.get<std::uint64_t>();
    // Each result takes more bytes than this; a count that no message of
    // this length can hold is refused before anything is allocated.
    if (count > bytes.size()) throw Error("truncated message between MPI ranks");
    for (std::uint64_t i = 0; i < count; ++i) message.results.push_back(get_result(in));
    return message;
}

MessageBytes encode(const FailureMessage& message) {
    Writer out;
    out.put(message.task);
    put_string(out, message.what);
    return std::move(out.bytes);
}

FailureMessage decode_failure(const MessageBytes& bytes) {
    Reader in(bytes);
    FailureMessage message;
    message.task = in.get<std::int32_t>();
    message.what = get_string(in);
    return message;
}

MessageBytes encode(const StopMessage& message) {
    Writer out;
    out.put<std::int32_t>(message.failed ? 1 : 0);
    return std::move(out.bytes);
}

StopMessage decode_stop(const MessageBytes& bytes) {
    Reader in(bytes);
    return StopMessage{in.get<std::int32_t>() != 0};
}

MessageBytes encode(const HeartbeatMessage& message) {
    Writer out;
    out.put(message.seconds);
    return std::move(out.bytes);
}

HeartbeatMessage decode_heartbeat(const MessageBytes& bytes) {
    Reader in(bytes);
    return HeartbeatMessage{in.get<double>()};
}

} // namespace tetiso
