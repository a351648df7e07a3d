# skinstream on Debian 12 in two stages. The builder (debian:12, scripts/install-deps.sh
# --build-only: compilers, CMake, the -dev packages, Node.js) compiles skinstreamd and the
# skinstream CLI, bundles the web page and makes the demo (make-demo.sh: the 25 s 350-marker
# capture of several motions and the demo subject). The runtime image (debian:12-slim) holds the
# daemon, the shared libraries it loads, the page and the demo, run by an unprivileged user: no
# compiler, test tool, Chromium or Blender. It replays the demo in a loop, the web viewer on 8480,
# TCP subscribers on 8481: docker run -p 8480:8480 -p 8481:8481 skinstream, then open
# http://localhost:8480/. bash scripts/image.sh builds it and checks its size and its daemon.
FROM debian:12 AS build
WORKDIR /src/skinstream
COPY scripts/install-deps.sh scripts/install-deps.sh
RUN bash scripts/install-deps.sh --build-only && rm -rf /var/lib/apt/lists/*
COPY . .
# The CPU level the image needs (AVX2 + FMA by default): --build-arg SKINSTREAM_CPU_LEVEL=x86-64
# for an image that runs on any x86-64 host. SKINSTREAM_BUILD_NICE: the compile's niceness (the
# engine runs it, not the docker client; scripts/image.sh passes 15).
ARG SKINSTREAM_CPU_LEVEL=x86-64-v3
ARG SKINSTREAM_BUILD_NICE=0
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF \
    -DSKINSTREAM_CPU_LEVEL="${SKINSTREAM_CPU_LEVEL}" \
 && nice -n "${SKINSTREAM_BUILD_NICE}" cmake --build build -j "$(nproc)" --target skinstreamd skinstream \
 && strip build/bin/skinstreamd \
 && bash clients/web/build.sh build/web \
 && bash scripts/make-demo.sh build/bin/skinstream build/demo

FROM debian:12-slim
# The shared libraries skinstreamd loads beyond libc, libstdc++ and libgcc (ldd build/bin/skinstreamd:
# libspdlog, libfmt, libmeshoptimizer, libcrypto, libexpat).
RUN apt-get update \
 && apt-get install -y --no-install-recommends libspdlog1.10 libfmt9 libmeshoptimizer2d libssl3 libexpat1 \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --user-group --no-create-home --home-dir /opt/skinstream --shell /usr/sbin/nologin skinstream
COPY --from=build /src/skinstream/build/bin/skinstreamd /opt/skinstream/bin/
COPY --from=build /src/skinstream/build/web /opt/skinstream/web
COPY --from=build /src/skinstream/build/demo/subject.sksubj /src/skinstream/build/demo/medley.c3d /opt/skinstream/demo/
WORKDIR /opt/skinstream
ENV PATH=/opt/skinstream/bin:$PATH
USER skinstream
EXPOSE 8480 8481
# GET /health with bash alone (no curl in the image).
HEALTHCHECK --interval=10s --timeout=5s --start-period=60s --retries=3 \
  CMD ["bash", "-c", "exec 3<>/dev/tcp/127.0.0.1/8480 && printf 'GET /health HTTP/1.1\\r\\nHost: localhost\\r\\nConnection: close\\r\\n\\r\\n' >&3 && grep -q '\"status\":\"ok\"' <&3"]
CMD ["skinstreamd", "--subject", "demo/subject.sksubj", "--replay", "demo/medley.c3d", "--loop", \
     "--web-root", "web", "--bind", "0.0.0.0", "--http-port", "8480", "--sub-port", "8481"]
