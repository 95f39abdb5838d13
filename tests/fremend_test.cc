// End-to-end tests of the daemon itself, against the real fremend: health, reflection, signals,
// configuration errors, message size limits, bearer tokens and TLS.
#include <gmock/gmock.h>
#include <google/protobuf/descriptor.pb.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "fremen/v1/maps.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "tests/fremend_fixture.h"
#include "tests/map_specs.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;
using HealthResponse = grpc::health::v1::HealthCheckResponse;
namespace reflection = grpc::reflection::v1alpha;

class FremendTest : public DaemonTest {
 protected:
  // The health of `service` ("" = the whole server); the call's status when it fails.
  grpc::Status Health(const std::string& service, HealthResponse::ServingStatus* serving) {
    auto stub = grpc::health::v1::Health::NewStub(daemon_->NewChannel());
    grpc::health::v1::HealthCheckRequest request;
    request.set_service(service);
    HealthResponse response;
    const grpc::Status status = stub->Check(CallContext().get(), request, &response);
    *serving = response.status();
    return status;
  }

  // One request on a reflection stream, and its answer.
  reflection::ServerReflectionResponse Reflect(const reflection::ServerReflectionRequest& request) {
    auto stub = reflection::ServerReflection::NewStub(daemon_->NewChannel());
    auto context = CallContext();
    auto stream = stub->ServerReflectionInfo(context.get());
    reflection::ServerReflectionResponse response;
    EXPECT_TRUE(stream->Write(request));
    EXPECT_TRUE(stream->WritesDone());
    EXPECT_TRUE(stream->Read(&response));
    const grpc::Status status = stream->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response;
  }
};

TEST_F(FremendTest, HealthIsServingForTheServerAndEachService) {
  HealthResponse::ServingStatus serving;
  ASSERT_TRUE(Health("", &serving).ok());
  EXPECT_EQ(serving, HealthResponse::SERVING);
  for (const char* service : {"fremen.v1.MapService", "fremen.v1.IngestService", "fremen.v1.QueryService",
                              "fremen.v1.AdminService"}) {
    ASSERT_TRUE(Health(service, &serving).ok()) << service;
    EXPECT_EQ(serving, HealthResponse::SERVING) << service;
  }
  // Services the daemon does not serve are unknown to health, as to gRPC.
  EXPECT_EQ(Health("fremen.v1.NoSuchService", &serving).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(FremendTest, ReflectionListsTheServices) {
  reflection::ServerReflectionRequest request;
  request.set_list_services("");
  const reflection::ServerReflectionResponse response = Reflect(request);
  std::vector<std::string> names;
  for (const auto& service : response.list_services_response().service()) names.push_back(service.name());
  EXPECT_THAT(names, ::testing::IsSupersetOf({"fremen.v1.MapService", "fremen.v1.IngestService",
                                              "fremen.v1.QueryService", "fremen.v1.AdminService",
                                              "grpc.health.v1.Health", "grpc.reflection.v1alpha.ServerReflection"}));
}

TEST_F(FremendTest, ReflectionDescribesTheApi) {
  reflection::ServerReflectionRequest request;
  request.set_file_containing_symbol("fremen.v1.MapService");
  const reflection::ServerReflectionResponse response = Reflect(request);
  ASSERT_GE(response.file_descriptor_response().file_descriptor_proto_size(), 1);
  bool found = false;
  for (const std::string& bytes : response.file_descriptor_response().file_descriptor_proto()) {
    google::protobuf::FileDescriptorProto file;
    ASSERT_TRUE(file.ParseFromString(bytes));
    if (file.name() != "fremen/v1/maps.proto") continue;
    found = true;
    ASSERT_EQ(file.service_size(), 1);
    std::vector<std::string> methods;
    for (const auto& method : file.service(0).method()) methods.push_back(method.name());
    EXPECT_THAT(methods, ::testing::ElementsAre("CreateMap", "GetMap", "ListMaps", "DeleteMap"));
  }
  EXPECT_TRUE(found);
}

TEST_F(FremendTest, SigtermStopsCleanlyWithExitCodeZero) {
  const int code = daemon_->Stop(SIGTERM);
  EXPECT_EQ(code, 0) << daemon_->Log();
  EXPECT_THAT(daemon_->Log(), HasSubstr("SIGTERM: shutting down"));
  EXPECT_THAT(daemon_->Log(), HasSubstr("[store] closed"));
  daemon_.reset();
}

TEST_F(FremendTest, SigintStopsCleanlyWithExitCodeZero) {
  EXPECT_EQ(daemon_->Stop(SIGINT), 0) << daemon_->Log();
  daemon_.reset();
}

TEST_F(FremendTest, ASecondDaemonCannotTakeTheSamePort) {
  TempDir other;
  const RunResult result = RunFremend({"--listen", daemon_->address(), "--data-dir", other.Path("data")});
  EXPECT_EQ(result.exit_code, 1) << Describe(result) << "\n" << result.err;
  EXPECT_THAT(result.err, HasSubstr("cannot listen on " + daemon_->address()));
}

TEST_F(FremendTest, ASecondDaemonCannotOpenTheSameDataDirectory) {
  const RunResult result = RunFremend({"--listen", "127.0.0.1:0", "--data-dir", data_dir()});
  EXPECT_EQ(result.exit_code, 1) << Describe(result) << "\n" << result.err;
  EXPECT_THAT(result.err, HasSubstr("is in use by another fremend (pid " + std::to_string(daemon_->pid()) + ")"));
  // The first daemon serves on.
  HealthResponse::ServingStatus serving;
  ASSERT_TRUE(Health("", &serving).ok());
  EXPECT_EQ(serving, HealthResponse::SERVING);
}

TEST_F(FremendTest, ConfigFileSettingsApply) {
  // A 1 MiB message limit from a config file: a 2 MiB request is refused, and the daemon serves on.
  StopDaemon();
  const std::string config = dir_.Write("fremend.conf", "# test\nmax_message_mb = 1\nlog_level = debug\n");
  StartDaemon({"--config", config});
  ASSERT_FALSE(HasFatalFailure());
  auto stub = v1::MapService::NewStub(daemon_->NewChannel());
  v1::CreateMapRequest request;
  request.mutable_map()->set_name(std::string(2 << 20, 'a'));
  v1::CreateMapResponse response;
  EXPECT_EQ(stub->CreateMap(CallContext().get(), request, &response).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  v1::ListMapsResponse list;
  EXPECT_TRUE(stub->ListMaps(CallContext().get(), v1::ListMapsRequest(), &list).ok());
}

TEST(FremendCommandLineTest, HelpExitsZero) {
  const RunResult result = RunFremend({"--help"});
  EXPECT_EQ(result.exit_code, 0) << Describe(result) << "\n" << result.err;
  EXPECT_THAT(result.out, HasSubstr("--listen"));
  EXPECT_THAT(result.out, HasSubstr("--data-dir"));
  EXPECT_THAT(result.out, HasSubstr("--config"));
  EXPECT_EQ(result.err, "");
}

TEST(FremendCommandLineTest, BadConfigurationExitsTwoNamingTheSetting) {
  RunResult result = RunFremend({"--listen", "abc"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_THAT(result.err, HasSubstr("config: listen: \"abc\" is not HOST:PORT"));

  TempDir dir;
  const std::string config = dir.Write("bad.conf", "listen = 127.0.0.1:0\nupdate_schedule = 0 25 * * *\n");
  result = RunFremend({"--config", config});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_THAT(result.err, HasSubstr("config: update_schedule: hour: 25 is outside [0, 23]"));
  EXPECT_THAT(result.err, HasSubstr("bad.conf line 2"));

  result = RunFremend({"--config", dir.Path("missing.conf")});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_THAT(result.err, HasSubstr("missing.conf"));

  result = RunFremend({"--no-such-flag"});
  EXPECT_EQ(result.exit_code, 2);
}

TEST(FremendCommandLineTest, UnwritableDataDirectoryExitsOne) {
  TempDir dir;
  const std::string file = dir.Write("not-a-directory", "");
  const RunResult result = RunFremend({"--listen", "127.0.0.1:0", "--data-dir", file + "/data"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("data_dir: cannot create"));
}

// --- bearer tokens ---

class FremendTokenTest : public DaemonTest {
 protected:
  void SetUp() override {
    const std::string tokens = dir_.Write("tokens", "# roles\nread:reader-token\nwrite:writer-token\n");
    StartDaemon({"--tokens-file", tokens});
    if (!HasFatalFailure()) stub_ = v1::MapService::NewStub(daemon_->NewChannel());
  }
  static std::vector<std::pair<std::string, std::string>> Bearer(const std::string& token) {
    return {{"authorization", "Bearer " + token}};
  }
  grpc::Status Create(const std::string& name, const std::vector<std::pair<std::string, std::string>>& metadata) {
    v1::CreateMapRequest request;
    *request.mutable_map() = GenericMapSpec(name);
    v1::CreateMapResponse response;
    return stub_->CreateMap(CallContext(metadata).get(), request, &response);
  }
  grpc::Status List(const std::vector<std::pair<std::string, std::string>>& metadata) {
    v1::ListMapsResponse response;
    return stub_->ListMaps(CallContext(metadata).get(), v1::ListMapsRequest(), &response);
  }
  std::unique_ptr<v1::MapService::Stub> stub_;
};

TEST_F(FremendTokenTest, MissingOrInvalidTokenIsUnauthenticated) {
  EXPECT_EQ(List({}).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(List(Bearer("guess")).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(List({{"authorization", "reader-token"}}).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(Create("lab", {}).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(FremendTokenTest, ReadTokenReadsButMayNotWrite) {
  EXPECT_TRUE(List(Bearer("reader-token")).ok());
  const grpc::Status create = Create("lab", Bearer("reader-token"));
  EXPECT_EQ(create.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(create.error_message(), HasSubstr("CreateMap needs a write token"));
}

TEST_F(FremendTokenTest, WriteTokenMayDoEverything) {
  ASSERT_TRUE(Create("lab", Bearer("writer-token")).ok());
  EXPECT_TRUE(List(Bearer("writer-token")).ok());
  v1::GetMapRequest get;
  get.set_map("lab");
  v1::GetMapResponse map;
  EXPECT_TRUE(stub_->GetMap(CallContext(Bearer("reader-token")).get(), get, &map).ok());
  v1::DeleteMapRequest del;
  del.set_map("lab");
  v1::DeleteMapResponse deleted;
  EXPECT_EQ(stub_->DeleteMap(CallContext(Bearer("reader-token")).get(), del, &deleted).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(stub_->DeleteMap(CallContext(Bearer("writer-token")).get(), del, &deleted).ok());
}

TEST_F(FremendTokenTest, HealthNeedsNoToken) {
  // Load balancers and orchestrators probe health without credentials.
  auto health = grpc::health::v1::Health::NewStub(daemon_->NewChannel());
  HealthResponse response;
  EXPECT_TRUE(health->Check(CallContext().get(), grpc::health::v1::HealthCheckRequest(), &response).ok());
  EXPECT_EQ(response.status(), HealthResponse::SERVING);
}

// --- TLS ---

TEST(FremendTlsTest, ServesTlsAndRefusesPlaintext) {
  TempDir dir;
  const std::optional<TestCertificate> certificate = MakeTestCertificate(dir);
  if (!certificate) GTEST_SKIP() << "openssl cannot make a test certificate";
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = certificate->cert_pem;
  auto started = FremendProcess::Start(dir.Path("data"),
                                       {"--tls-cert-file", certificate->cert_path, "--tls-key-file", certificate->key_path},
                                       grpc::SslCredentials(options));
  ASSERT_TRUE(started.ok()) << started.status();
  auto& daemon = *started;
  EXPECT_THAT(daemon->Log(), HasSubstr("with TLS"));

  v1::ListMapsResponse response;
  auto secure = v1::MapService::NewStub(daemon->NewChannel());
  EXPECT_TRUE(secure->ListMaps(CallContext().get(), v1::ListMapsRequest(), &response).ok());
  auto plain = v1::MapService::NewStub(grpc::CreateChannel(daemon->address(), grpc::InsecureChannelCredentials()));
  EXPECT_EQ(plain->ListMaps(CallContext({}, std::chrono::seconds(5)).get(), v1::ListMapsRequest(), &response)
                .error_code(),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(daemon->Stop(), 0) << daemon->Log();
}

}  // namespace
}  // namespace fremen::testing
