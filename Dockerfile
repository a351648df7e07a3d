# skinstream on Debian 12, built with the same scripts the README uses: the daemon replaying the
# 25 s 350-marker demo capture (several motions, made by make-demo.sh) with the demo subject, the web viewer on 8480, TCP subscribers on
# 8481. docker run -p 8480:8480 -p 8481:8481 skinstream, then open http://localhost:8480/.
FROM debian:12
WORKDIR /src/skinstream
COPY scripts/install-deps.sh scripts/install-deps.sh
RUN bash scripts/install-deps.sh && rm -rf /var/lib/apt/lists/*
COPY . .
# The CPU level the image needs (AVX2 + FMA by default): --build-arg SKINSTREAM_CPU_LEVEL=x86-64
# for an image that runs on any x86-64 host.
ARG SKINSTREAM_CPU_LEVEL=x86-64-v3
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF \
    -DSKINSTREAM_CPU_LEVEL="${SKINSTREAM_CPU_LEVEL}" \
 && cmake --build build -j "$(nproc)" \
 && bash clients/web/build.sh build/web \
 && bash scripts/make-demo.sh build/bin/skinstream build/demo
ENV PATH=/src/skinstream/build/bin:$PATH
EXPOSE 8480 8481
CMD ["skinstreamd", "--subject", "build/demo/subject.sksubj", "--replay", "build/demo/medley.c3d", "--loop", \
     "--web-root", "build/web", "--bind", "0.0.0.0", "--http-port", "8480", "--sub-port", "8481"]
