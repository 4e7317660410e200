# The web UI build, run by the build of `tessera`: copies web/'s sources into the
# build folder (SRC -> DIR/src), installs the npm packages of web/package-lock.json there
# (`npm ci`, only when the lock changed; offline from npm's cache when it has them), and
# runs Vite, leaving DIR/dist for cmake/embed_assets.cmake. SCENES: the example scenes.
set(work ${DIR}/src)
file(MAKE_DIRECTORY ${work})
foreach(f index.html vite.config.js package.json package-lock.json)
  configure_file(${SRC}/${f} ${work}/${f} COPYONLY)
endforeach()
file(COPY ${SRC}/src DESTINATION ${work})
find_program(NPM npm)
find_program(NODE node)
if(NOT NPM OR NOT NODE)
  message(FATAL_ERROR "web UI: node and npm are needed to build web/ (Debian: apt-get install nodejs npm); "
                      "configure with -DTS_WEB=OFF for a tessera without the UI")
endif()
set(stamp ${work}/node_modules/.tessera-installed-lock)
file(READ ${work}/package-lock.json lock)
set(installed "")
if(EXISTS ${stamp})
  file(READ ${stamp} installed)
endif()
if(NOT lock STREQUAL installed)
  message(STATUS "web UI: npm ci in ${work}")
  execute_process(COMMAND ${NPM} ci --prefer-offline --no-audit --no-fund --loglevel=error
                  WORKING_DIRECTORY ${work} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "web UI: `npm ci` failed in ${work} (no network and no npm cache?); "
                        "configure with -DTS_WEB=OFF for a tessera without the UI")
  endif()
  file(WRITE ${stamp} "${lock}")
endif()
set(ENV{TS_SCENES_DIR} ${SCENES})
set(ENV{TS_WEB_OUT} ${DIR}/dist)
execute_process(COMMAND ${NODE} node_modules/vite/bin/vite.js build --logLevel warn
                WORKING_DIRECTORY ${work} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "web UI: the Vite build failed")
endif()
