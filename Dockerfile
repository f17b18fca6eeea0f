# cadsynth in a container (docs/install.md, "Docker and Apptainer"): Debian 12, the project's own setup
# script, a Release build installed to /usr/local (the executable, the Python module, the shipped
# recipes in /usr/local/share/cadsynth/recipes).
#   docker build -t cadsynth .
#   docker run --rm -v "$PWD/out:/out" cadsynth generate -o /out/default
#   apptainer build cadsynth.sif docker-daemon://cadsynth:latest
FROM debian:12
COPY . /src/cadsynth
RUN /src/cadsynth/tools/setup.sh \
 && cmake -S /src/cadsynth -B /src/build -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCADSYNTH_BUILD_TESTS=OFF -DCADSYNTH_BUILD_BENCHMARKS=OFF \
 && cmake --build /src/build \
 && cmake --install /src/build --prefix /usr/local \
 && rm -rf /src/build /var/lib/apt/lists/*
# The part cache is ~/.cache/cadsynth (/root/.cache/cadsynth here; under Apptainer, the user's
# own): mount a volume there to keep it between runs.
WORKDIR /work
ENTRYPOINT ["cadsynth"]
CMD ["--help"]
