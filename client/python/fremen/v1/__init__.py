"""fremen.v1: the API's generated messages (*_pb2) and gRPC stubs (*_pb2_grpc).

Only this file lives in the source tree: the build (proto/CMakeLists.txt) writes the generated
modules beside its copy in <build>/python/fremen/v1/.
"""
