#include "device/udp_socket.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <string>
#include <vector>

#include "loop/test_poll.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

std::string AddressErrorOf(const std::string& text) {
  try {
    ParseUdpAddress(text, "--listen");
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(UdpSocket, ParsesIpv4AndLocalhost) {
  const UdpEndpoint a = ParseUdpAddress("udp://127.0.0.1:47000", "x");
  EXPECT_EQ(a.address, 0x7f000001u);
  EXPECT_EQ(a.port, 47000);
  EXPECT_TRUE(a.IsLoopback());
  EXPECT_EQ(a.ToString(), "udp://127.0.0.1:47000");
  const UdpEndpoint b = ParseUdpAddress("udp://localhost:0", "x");
  EXPECT_EQ(b.address, 0x7f000001u);
  EXPECT_EQ(b.port, 0);
  const UdpEndpoint c = ParseUdpAddress("udp://192.168.1.20:65535", "x");
  EXPECT_EQ(c.address, 0xc0a80114u);
  EXPECT_EQ(c.port, 65535);
  EXPECT_FALSE(c.IsLoopback());
  EXPECT_TRUE(ParseUdpAddress("udp://127.8.9.10:1", "x").IsLoopback());
}

TEST(UdpSocket, MalformedAddressesNameTheTextAndOption) {
  for (const std::string text :
       {"127.0.0.1:5000", "udp://127.0.0.1", "udp://127.0.0.1:", "udp://:5000",
        "udp://127.0.0.1:70000", "udp://127.0.0.1:12a", "udp://127.0.0.1:-1", "udp://host:1",
        "udp://256.0.0.1:1", "tcp://127.0.0.1:1", ""}) {
    const std::string message = AddressErrorOf(text);
    EXPECT_NE(message.find("'" + text + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("--listen"), std::string::npos) << message;
    EXPECT_NE(message.find("[0, 65535]"), std::string::npos) << message;
  }
}

TEST(UdpSocket, NonLoopbackNeedsTheExplicitOption) {
  const UdpEndpoint any = ParseUdpAddress("udp://0.0.0.0:0", "x");
  try {
    RequireLoopbackUnlessAllowed(any, "--listen", false);
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("udp://0.0.0.0:0"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("allow_non_loopback"), std::string::npos);
  }
  EXPECT_NO_THROW(RequireLoopbackUnlessAllowed(any, "--listen", true));
  EXPECT_NO_THROW(
      RequireLoopbackUnlessAllowed(ParseUdpAddress("udp://127.0.0.1:1", "x"), "--listen", false));
}

TEST(UdpSocket, BindsAnEphemeralPortAndExchangesDatagrams) {
  UdpSocket a(ParseUdpAddress("udp://127.0.0.1:0", "a"), "a");
  UdpSocket b(ParseUdpAddress("udp://127.0.0.1:0", "b"), "b");
  EXPECT_NE(a.local().port, 0);
  EXPECT_NE(a.local().port, b.local().port);

  std::vector<std::uint8_t> buffer(16);
  Datagram datagram;
  EXPECT_EQ(b.Receive(buffer, &datagram), EAGAIN);

  const std::vector<std::uint8_t> message = {1, 2, 3, 4, 5};
  ASSERT_EQ(a.SendTo(message, b.local()), 0);
  ASSERT_TRUE(testing::PollUntil([&] { return b.Receive(buffer, &datagram) == 0; }));
  EXPECT_EQ(datagram.bytes, 5u);
  EXPECT_EQ(datagram.full_bytes, 5u);
  EXPECT_EQ(datagram.source, a.local());
  EXPECT_EQ(std::vector<std::uint8_t>(buffer.begin(), buffer.begin() + 5), message);

  // a datagram longer than the buffer reports its full length
  const std::vector<std::uint8_t> long_message(100, 7);
  ASSERT_EQ(a.SendTo(long_message, b.local()), 0);
  ASSERT_TRUE(testing::PollUntil([&] { return b.Receive(buffer, &datagram) == 0; }));
  EXPECT_EQ(datagram.bytes, 16u);
  EXPECT_EQ(datagram.full_bytes, 100u);
}

TEST(UdpSocket, AddressInUseNamesTheAddress) {
  UdpSocket first(ParseUdpAddress("udp://127.0.0.1:0", "first"), "first");
  const std::string address = first.local().ToString();
  try {
    UdpSocket second(first.local(), "--listen");
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(address), std::string::npos) << message;
    EXPECT_NE(message.find("--listen"), std::string::npos) << message;
    EXPECT_NE(message.find("in use"), std::string::npos) << message;
  }
}

TEST(UdpSocket, MoveKeepsTheSocket) {
  UdpSocket a(ParseUdpAddress("udp://127.0.0.1:0", "a"), "a");
  const UdpEndpoint local = a.local();
  UdpSocket b(std::move(a));
  EXPECT_EQ(b.local(), local);
  UdpSocket c(ParseUdpAddress("udp://127.0.0.1:0", "c"), "c");
  ASSERT_EQ(c.SendTo(std::vector<std::uint8_t>{9}, b.local()), 0);
  std::vector<std::uint8_t> buffer(4);
  Datagram datagram;
  ASSERT_TRUE(testing::PollUntil([&] { return b.Receive(buffer, &datagram) == 0; }));
  EXPECT_EQ(buffer[0], 9);
}

}  // namespace
}  // namespace rigidtouch::device
