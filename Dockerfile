# paraspace: the explorer (viser, port 8080) and the REST API (FastAPI, port 8081) in one container.
#
#   docker build -t paraspace .
#   docker run --rm -p 127.0.0.1:8080:8080 -p 127.0.0.1:8081:8081 paraspace   (loopback only: no authentication)
#   open http://localhost:8080 (explorer) and http://localhost:8081/docs (API)
#
# Everything comes from the package registries (the base image, PyPI): no other downloads.
# The base image is pinned by digest (a tag moves; a digest does not): the python:3.11-slim image
# index in use in 2026. To move to a newer one: `docker buildx imagetools inspect python:3.11-slim`
# and replace the digest (then run the tests).
# The dependency versions are pinned by a pip constraints file written below (the versions the
# test suite ran with) and installed from requirements.lock, each with its sha256; the project
# itself is installed as the README's `pip install .` does (without fetching a build backend).
FROM python:3.11-slim@sha256:9c900dea9e8fb7e16277c179b555cc72d29a352dbc33cff48ad5a0412fd5bfc7

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PIP_CONSTRAINT=/opt/paraspace/constraints.txt \
    NUMBA_CACHE_DIR=/home/paraspace/.cache/numba \
    MPLCONFIGDIR=/home/paraspace/.cache/matplotlib

# Pinned runtime dependencies (closure of pyproject's [project.dependencies]).
RUN mkdir -p /opt/paraspace && printf '%s\n' \
        annotated-doc==0.0.7 annotated-types==0.8.0 anyio==4.16.0 certifi==2026.10.18 \
        charset-normalizer==3.5.2 click==8.5.1 cloudpickle==3.1.2 contourpy==1.3.3 cycler==0.12.1 \
        dask==2026.8.0 distributed==2026.8.0 fast-simplification==0.2.0 fastapi==0.165.0 fastapi-offline==1.7.7 \
        fonttools==4.68.0 fsspec==2026.9.0 h11==0.16.0 idna==3.20 imageio==2.38.1 \
        importlib-metadata==10.2.0 jinja2==3.1.6 kiwisolver==1.5.1 lazy-importer==0.1.0 \
        lazy-loader==0.6 llvmlite==0.50.0 locket==1.0.0 markdown-it-py==4.3.0 markupsafe==3.0.4 \
        matplotlib==3.11.2 mdurl==0.1.2 msgpack==1.2.4 msgspec==0.22.0 \
        networkx==3.6.1 numba==0.68.1 numpy==2.4.6 opentelemetry-api==1.45.2 packaging==26.3 \
        partd==1.4.2 pillow==13.0.0 psutil==7.2.2 pydantic==2.14.3 \
        pydantic-core==2.50.4 pygments==2.21.0 pyparsing==3.3.3 python-dateutil==4.0.0 \
        pyyaml==6.0.3 requests==2.34.2 rich==14.3.4 scikit-image==0.26.0 scipy==1.17.1 \
        sortedcontainers==2.4.0 starlette==1.10.0 tblib==3.2.2 tifffile==2026.3.3 toolz==1.2.0 \
        tornado==6.6.1 tqdm==4.70.1 trimesh==5.2.0 typing-extensions==4.16.0 \
        typing-inspection==0.4.5 tzdata==2026.6 urllib3==2.8.0 uvicorn==0.54.0 viser==1.1.1 \
        websockets==16.1.1 zict==3.0.0 zipp==4.1.2 zstandard==0.25.0 \
        pymoo==0.6.2 plotly==7.1.0 narwhals==2.29.0 moocore==0.3.2 cffi==2.1.1 pycparser==3.12 platformdirs==4.14.7 cma==4.5.0 autograd==1.9.1 alive-progress==3.3.0 about-time==4.2.1 graphemeu==0.7.2 deprecated==1.3.1 wrapt==2.5.2 \
        | tr ' ' '\n' | sed '/^$/d' > /opt/paraspace/constraints.txt

# libgomp1 (Debian's package) gives numba its OpenMP threading layer; without it numba falls
# back to "workqueue" (still safe: kinematics.parallel serialises kernel launches, but slower).
RUN apt-get update && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/*

RUN useradd --create-home --uid 10001 --shell /usr/sbin/nologin paraspace \
    && mkdir -p /home/paraspace/.cache/numba /home/paraspace/.cache/matplotlib \
    && chown -R paraspace:paraspace /home/paraspace/.cache

# Every dependency (and the build backend) from requirements.lock, each wheel checked against its
# sha256 (linux x86_64 wheels); then the project itself with that backend (no other download).
COPY requirements.lock /opt/paraspace/requirements.lock
RUN pip install --require-hashes --no-deps -r /opt/paraspace/requirements.lock
WORKDIR /opt/paraspace/src
COPY . .
RUN pip install --no-build-isolation . \
    && cd / && rm -rf /opt/paraspace/src

USER paraspace
WORKDIR /home/paraspace
# Compile the numba kernels once into the (writable) cache, so the first request is fast.
RUN python -c "from paraspace.kinematics.workspace import warm_up; print('numba warm-up', round(warm_up(), 1), 's')"

EXPOSE 8080 8081
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(0 if urllib.request.urlopen('http://127.0.0.1:8081/api/v1/health', timeout=4).status == 200 else 1)"]
ENTRYPOINT ["paraspace", "serve", "--host", "0.0.0.0", "--port", "8080", "--api-port", "8081"]
