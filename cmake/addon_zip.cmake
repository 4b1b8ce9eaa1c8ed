# Writes the installable add-on: a zip holding the folder photonsplat/ (the Python package and the compiled
# module), which Blender's Preferences > Add-ons > Install unpacks into the user's add-ons folder.
# Run by the addon_zip target:  cmake -DSOURCE=... -DMODULE=... -DSTAGE=... -DOUTPUT=... -P addon_zip.cmake
file(REMOVE_RECURSE "${STAGE}")
file(MAKE_DIRECTORY "${STAGE}")
file(COPY "${SOURCE}" DESTINATION "${STAGE}" PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE)
file(COPY "${MODULE}" DESTINATION "${STAGE}/photonsplat")
file(REMOVE "${OUTPUT}")
# Archive members are named relative to the working directory: run from the stage so they start photonsplat/.
execute_process(COMMAND "${CMAKE_COMMAND}" -E tar cf "${OUTPUT}" --format=zip photonsplat
                WORKING_DIRECTORY "${STAGE}" RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "could not write ${OUTPUT}")
endif()
