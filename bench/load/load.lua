-- bench/load/load.lua — one load group of bench/load/run.sh, as a wrk script.
--
--   wrk -t1 -cN -dCAP --latency -s load.lua URL -- GROUP OUT ID_A ID_B TILES_X TILES_Y MAX_BODY DELAY_MS
--
-- GROUP picks the requests, cycled deterministically (no randomness, so two runs send the
-- same sequence):
--   status   GET /api/v1/jobs/{id} of both jobs
--   list     GET /api/v1/jobs
--   metrics  GET /metrics
--   image    GET image.png, image.exr, tiles/{tx}/{ty}.png, tiles/{tx}/{ty}.exr of both jobs
--   bad      requests that must get a 4xx: malformed and invalid scenes, wrong content type,
--            empty and oversized bodies, unknown routes, methods not allowed, unknown and
--            malformed job ids, tiles out of range (none of them creates or cancels a job)
-- DELAY_MS > 0 makes each connection wait that long between requests (the bad stream runs
-- at a bounded rate; the other groups run closed-loop, as fast as answers come).
--
-- At the end it writes OUT (one line, key=value pairs: requests, duration, latency
-- percentiles, status classes, socket errors) and OUT.hist (latency histogram, "µs count"
-- per line, for run.sh to merge the groups' percentiles). Status classes are counted from
-- the responses only for the bad group (2xx/4xx/5xx); for the others wrk's own count of
-- non-2xx/3xx answers is the check, since a response hook makes wrk hand every image body
-- to Lua, which would cost the load generator more CPU than the server it measures.

local threads = {}

function setup(thread)
    threads[#threads + 1] = thread
end

local paths = {}
local bad = {}
local n = 0

local function bad_cases(id_a, max_body)
    local json = { ["Content-Type"] = "application/json" }
    local big = '{"tessera": 1, "pad": "' .. string.rep("x", max_body + 1024) .. '"}'
    local api = "/api/v1/jobs"
    return {
        { "POST", api, json, '{"tessera": 1, "camera": ' },                    -- malformed JSON: 400
        { "POST", api, json, '{"tessera": 1, "film": {"width": -4}}' },         -- invalid scene: 400
        { "POST", api, json, '[1, 2, 3]' },                                     -- not an object: 400
        { "POST", api, { ["Content-Type"] = "image/png" }, '{"tessera": 1}' },  -- wrong type: 415
        { "POST", api, json, "" },                                              -- empty body: 400
        { "POST", api, json, big },                                             -- oversized: 413
        { "GET", "/api/v1/nothing-here", nil, nil },                            -- unknown route: 404
        { "GET", "/api/v2/jobs", nil, nil },                                    -- unknown version: 404
        { "PUT", api, json, "{}" },                                             -- method: 405
        { "PATCH", api .. "/" .. id_a, json, "{}" },                            -- method: 405
        { "DELETE", "/metrics", nil, nil },                                     -- method: 405
        { "POST", api .. "/" .. id_a .. "/image.png", json, "{}" },             -- method: 405
        { "GET", api .. "/0123456789abcdef", nil, nil },                        -- unknown id: 404
        { "DELETE", api .. "/fedcba9876543210", nil, nil },                     -- unknown id: 404
        { "GET", api .. "/not%20an%20id/image.exr", nil, nil },                 -- malformed id: 404
        { "GET", api .. "/" .. string.rep("a", 64), nil, nil },                 -- id too long: 404
        { "GET", api .. "/" .. id_a .. "/tiles/999/999.png", nil, nil },        -- no such tile: 404
        { "GET", api .. "/" .. id_a .. "/tiles/-1/0.exr", nil, nil },           -- no such tile: 404
        { "GET", api .. "/" .. id_a .. "/tiles/a/b.png", nil, nil },            -- not a tile: 404
        { "GET", api .. "/" .. id_a .. "/image.gif", nil, nil },                -- no such format: 404
    }
end

function init(args)
    group = args[1]
    out = args[2]
    local id_a, id_b = args[3], args[4]
    local tiles_x, tiles_y = tonumber(args[5]), tonumber(args[6])
    local max_body = tonumber(args[7])
    local delay_ms = tonumber(args[8]) or 0
    if delay_ms > 0 then
        -- Defined only when wanted: with a delay() wrk puts every request through a timer,
        -- which costs the closed-loop groups a third of their rate.
        delay = function() return delay_ms end
    end
    c2, c3, c4, c5 = 0, 0, 0, 0
    local api = "/api/v1/jobs/"
    if group == "status" then
        paths = { api .. id_a, api .. id_b }
    elseif group == "list" then
        paths = { "/api/v1/jobs" }
    elseif group == "metrics" then
        paths = { "/metrics" }
    elseif group == "image" then
        -- Whole images and tiles alternate; the tiles walk the grid with a stride coprime
        -- to its size so every tile is asked for.
        local ntiles = tiles_x * tiles_y
        for i = 0, ntiles - 1 do
            local t = (i * 7) % ntiles
            local tx, ty = t % tiles_x, math.floor(t / tiles_x)
            for _, id in ipairs({ id_a, id_b }) do
                local stem = api .. id .. "/"
                paths[#paths + 1] = stem .. (i % 2 == 0 and "image.png" or "image.exr")
                paths[#paths + 1] = stem .. "tiles/" .. tx .. "/" .. ty .. (i % 2 == 0 and ".exr" or ".png")
            end
        end
    elseif group == "bad" then
        bad = bad_cases(id_a, max_body)
        response = function(status)
            if status >= 500 then c5 = c5 + 1
            elseif status >= 400 then c4 = c4 + 1
            elseif status >= 300 then c3 = c3 + 1
            else c2 = c2 + 1 end
        end
    else
        error("load.lua: unknown group " .. tostring(group))
    end
end

function request()
    n = n + 1
    if group == "bad" then
        local b = bad[(n - 1) % #bad + 1]
        return wrk.format(b[1], b[2], b[3], b[4])
    end
    return wrk.format("GET", paths[(n - 1) % #paths + 1])
end

function done(summary, latency, requests)
    local t = threads[1]
    local g, o = t:get("group"), t:get("out")
    local k2, k3, k4, k5 = 0, 0, 0, 0
    for _, th in ipairs(threads) do
        k2, k3, k4, k5 = k2 + th:get("c2"), k3 + th:get("c3"), k4 + th:get("c4"), k5 + th:get("c5")
    end
    local e = summary.errors
    local f = assert(io.open(o, "w"))
    f:write(string.format("group=%s requests=%d duration_us=%d bytes=%d p50_us=%d p90_us=%d p99_us=%d max_us=%d "
                          .. "mean_us=%.1f non2xx=%d c2xx=%d c3xx=%d c4xx=%d c5xx=%d connect=%d read=%d write=%d timeout=%d\n",
                          g, summary.requests, summary.duration, summary.bytes, latency:percentile(50),
                          latency:percentile(90), latency:percentile(99), latency.max, latency.mean, e.status,
                          k2, k3, k4, k5, e.connect, e.read, e.write, e.timeout))
    f:close()
    local h = assert(io.open(o .. ".hist", "w"))
    for i = 1, #latency do
        local v, c = latency(i)
        h:write(string.format("%d %d\n", v, c))
    end
    h:close()
end
