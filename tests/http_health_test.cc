// fremend's HTTP port end to end: the probes, the port's own setting, and TLS with the daemon's
// certificate — a real daemon, a real HTTP client (cpp-httplib's) on loopback.
#include <httplib.h>

#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/fremend_fixture.h"
#include "tests/http_client.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;

class HttpHealthTest : public DaemonTest {};

TEST_F(HttpHealthTest, LivenessAndReadinessAnswerOnceServing) {
  ASSERT_FALSE(daemon_->http_address().empty()) << daemon_->Log();
  httplib::Client client = HttpClientFor(daemon_->http_address());
  const httplib::Result healthz = client.Get("/healthz");
  ASSERT_TRUE(healthz) << httplib::to_string(healthz.error());
  EXPECT_EQ(healthz->status, 200);
  EXPECT_EQ(healthz->body, "ok\n");
  const httplib::Result readyz = client.Get("/readyz");
  ASSERT_TRUE(readyz) << httplib::to_string(readyz.error());
  EXPECT_EQ(readyz->status, 200);
  EXPECT_EQ(readyz->body, "ready\n");
  EXPECT_EQ(client.Get("/no-such-page")->status, 404);
}

TEST_F(HttpHealthTest, AnEmptyHttpListenServesNoHttpPort) {
  StopDaemon();
  StartDaemon({"--http-listen", ""});
  EXPECT_EQ(daemon_->http_address(), "");
  EXPECT_THAT(daemon_->Log(), HasSubstr("no HTTP port (http_listen is empty)"));
}

TEST_F(HttpHealthTest, ADaemonWhoseHttpPortIsTakenDoesNotStartAndSaysWhy) {
  const RunResult second = RunFremend(
      {"--listen", "127.0.0.1:0", "--http-listen", daemon_->http_address(), "--data-dir", dir_.Path("other")});
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_THAT(second.out + second.err, HasSubstr("http_listen: cannot listen on " + daemon_->http_address()));
}

TEST(HttpTlsTest, TheHttpPortServesTlsWithTheDaemonsCertificate) {
  TempDir dir;
  const std::optional<TestCertificate> certificate = MakeTestCertificate(dir);
  if (!certificate) GTEST_SKIP() << "openssl cannot make a test certificate";
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = certificate->cert_pem;
  auto started = FremendProcess::Start(
      dir.Path("data"), {"--tls-cert-file", certificate->cert_path, "--tls-key-file", certificate->key_path},
      grpc::SslCredentials(options));
  ASSERT_TRUE(started.ok()) << started.status();
  const std::string address = (*started)->http_address();
  const HostPort split = SplitHostPort(address);
  httplib::SSLClient secure(split.host, split.port);
  secure.set_ca_cert_path(certificate->cert_path.c_str());
  secure.enable_server_certificate_verification(true);
  const httplib::Result over_tls = secure.Get("/healthz");
  ASSERT_TRUE(over_tls) << httplib::to_string(over_tls.error());
  EXPECT_EQ(over_tls->status, 200);

  httplib::Client plain = HttpClientFor(address);
  EXPECT_FALSE(plain.Get("/healthz")) << "plain HTTP must not be answered on a TLS port";
  EXPECT_EQ((*started)->Stop(), 0);
}

}  // namespace
}  // namespace fremen::testing
