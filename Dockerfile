# skinstream on Debian 12, built with the same install script the README uses.
FROM debian:12
WORKDIR /src/skinstream
COPY scripts/install-deps.sh scripts/install-deps.sh
RUN bash scripts/install-deps.sh && rm -rf /var/lib/apt/lists/*
COPY . .
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DSKINSTREAM_BUILD_TESTS=OFF -DSKINSTREAM_BUILD_BENCHMARKS=OFF \
 && cmake --build build -j "$(nproc)"
ENV PATH=/src/skinstream/build/bin:$PATH
# Until the daemon lands: the bundled gap-filling demo.
CMD ["bash", "-c", "skinstream build-subject --capture replay_data/cmu/85_12.c3d --out /tmp/s.subject && skinstream eval-fill --capture replay_data/cmu/85_02.c3d --train replay_data/cmu/85_12.c3d"]
