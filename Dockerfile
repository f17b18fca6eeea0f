# cadsynth's container image (README, "Containers"): Debian 12, two stages.
#   build:   the project's setup script (tools/setup.sh --image: compilers and -dev packages,
#            no PyTorch), a Release build installed to /usr/local, and the list of the Debian
#            packages whose shared libraries the executable and the Python module load
#   runtime: Debian 12 with only those packages, python3 and numpy (no documentation, and no
#            Mesa: tools/container/); /usr/local from the build
#            stage; no compilers; runs as the user cadsynth (uid 1000), writing under /out only
#            (the part cache too: CADSYNTH_CACHE=/out/.cadsynth_cache)
# tools/container.sh builds it without a registry or a daemon (a Debian 12 base from debootstrap,
# buildah bud) and checks it. With Docker or Podman and a registry:
#   docker build -t cadsynth .
#   docker run --rm --read-only -v "$PWD/out:/out" cadsynth generate -o /out/default
ARG BASE=debian:12
FROM ${BASE} AS build
COPY . /src/cadsynth
RUN /src/cadsynth/tools/setup.sh --image \
 && cmake -S /src/cadsynth -B /src/build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCADSYNTH_BUILD_TESTS=OFF -DCADSYNTH_BUILD_BENCHMARKS=OFF \
 && cmake --build /src/build \
 && cmake --install /src/build --prefix /usr/local --strip \
 && /src/cadsynth/tools/container/runtime_packages.sh /usr/local > /src/runtime-packages.txt

FROM ${BASE}
COPY --from=build /src/runtime-packages.txt /tmp/runtime-packages.txt
# No documentation, manuals, translations or OpenCASCADE samples (tools/container/dpkg-slim.cfg),
# and an empty package in Mesa's place (tools/container/no-mesa.control): 931 MB before both.
COPY tools/container/dpkg-slim.cfg /etc/dpkg/dpkg.cfg.d/cadsynth-slim
COPY tools/container/no-mesa.control /tmp/no-mesa/DEBIAN/control
RUN dpkg-deb --build /tmp/no-mesa /tmp/no-mesa.deb > /dev/null && dpkg -i /tmp/no-mesa.deb \
 && apt-get update -q \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
      python3 python3-numpy $(cat /tmp/runtime-packages.txt) \
 && rm -rf /var/lib/apt/lists/* /var/cache/apt/archives/*.deb /tmp/runtime-packages.txt \
      /tmp/no-mesa /tmp/no-mesa.deb \
 && useradd --create-home --uid 1000 cadsynth \
 && mkdir /out && chown cadsynth:cadsynth /out
COPY --from=build /usr/local /usr/local
ENV CADSYNTH_CACHE=/out/.cadsynth_cache
USER cadsynth
WORKDIR /out
ENTRYPOINT ["cadsynth"]
CMD ["--help"]
