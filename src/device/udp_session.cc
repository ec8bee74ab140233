#include "device/udp_session.h"

#include <algorithm>

namespace rigidtouch::device {

void UdpSession::Open(std::uint64_t client_nonce, std::uint64_t server_nonce) {
  live_ = true;
  client_nonce_ = client_nonce;
  server_nonce_ = server_nonce;
  sent_counter_ = 0;
  received_counter_ = 0;
  has_sequence_ = false;
  newest_sequence_ = 0;
}

PacketHeader UdpSession::NextHeader(PacketType type) {
  return PacketHeader{type, client_nonce_, server_nonce_, ++sent_counter_};
}

SequenceOrder UdpSession::Order(std::uint64_t sequence) const {
  if (!has_sequence_) return SequenceOrder::kFirst;
  if (sequence > newest_sequence_) return SequenceOrder::kNewer;
  return sequence == newest_sequence_ ? SequenceOrder::kEqual : SequenceOrder::kOlder;
}

void UdpSession::Accept(std::uint64_t sequence) {
  has_sequence_ = true;
  newest_sequence_ = sequence;
}

const HandshakeMemory::Challenge* HandshakeMemory::Pending(const UdpEndpoint& source,
                                                           std::uint64_t client_nonce) const {
  for (const Challenge& c : pending_) {
    if (c.client_nonce != 0 && c.client_nonce == client_nonce && c.source == source) return &c;
  }
  return nullptr;
}

bool HandshakeMemory::Seen(std::uint64_t client_nonce) const {
  return std::find(seen_.begin(), seen_.end(), client_nonce) != seen_.end();
}

const HandshakeMemory::Challenge& HandshakeMemory::Remember(const UdpEndpoint& source,
                                                            std::uint64_t client_nonce,
                                                            std::uint64_t server_nonce,
                                                            std::int64_t now_ns) {
  seen_[next_seen_] = client_nonce;
  next_seen_ = (next_seen_ + 1) % seen_.size();
  Challenge& slot = pending_[next_pending_];
  next_pending_ = (next_pending_ + 1) % pending_.size();
  slot = Challenge{source, client_nonce, server_nonce, now_ns};
  return slot;
}

bool HandshakeMemory::Confirm(const UdpEndpoint& source, std::uint64_t client_nonce,
                              std::uint64_t server_nonce, std::int64_t now_ns,
                              std::int64_t max_age_ns) {
  for (Challenge& c : pending_) {
    if (c.client_nonce == 0 || c.client_nonce != client_nonce || c.source != source) continue;
    const bool answers = c.server_nonce == server_nonce && now_ns - c.sent_ns <= max_age_ns;
    if (answers) c = Challenge{};  // each challenge confirms one session, once
    return answers;
  }
  return false;
}

}  // namespace rigidtouch::device
