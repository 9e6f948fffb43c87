# `cmake --install BUILD [--prefix P]`: the command, its modules, the public API (libsdfc.so,
# <sdfc/sdfc.hpp>, find_package(sdfc) -> sdfc::sdfc, pkg-config sdfc), the man page and the
# shell completions, each where such files usually go. Included by the top CMakeLists.txt.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS sdfc RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(SDFC_MODULES)
  # lib/sdfc beside bin/: where runtime/io/module.cpp looks, whatever the libdir is called.
  install(TARGETS sdfc_image sdfc_preview LIBRARY DESTINATION lib/sdfc)
endif()
install(TARGETS sdfc_api EXPORT sdfcTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES runtime/api/sdfc.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sdfc)
install(EXPORT sdfcTargets NAMESPACE sdfc:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sdfc)
configure_package_config_file(runtime/api/sdfcConfig.cmake.in ${CMAKE_BINARY_DIR}/sdfcConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sdfc)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/sdfcConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/sdfcConfig.cmake ${CMAKE_BINARY_DIR}/sdfcConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sdfc)
# Relative to the .pc file itself: the tree may be installed with --prefix anywhere.
file(RELATIVE_PATH SDFC_PC_UP "${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig" "${CMAKE_INSTALL_PREFIX}")
string(REGEX REPLACE "/$" "" SDFC_PC_UP "${SDFC_PC_UP}")
configure_file(runtime/api/sdfc.pc.in ${CMAKE_BINARY_DIR}/sdfc.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/sdfc.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
# Made by sdfc after it links (CMakeLists.txt): from its option table.
install(FILES ${SDFC_SHARE}/man/man1/sdfc.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(FILES ${SDFC_SHARE}/bash-completion/completions/sdfc DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions)
install(FILES ${SDFC_SHARE}/zsh/site-functions/_sdfc DESTINATION ${CMAKE_INSTALL_DATADIR}/zsh/site-functions)
# The editor grammar (TextMate: VS Code, Sublime Text, GitHub) and the VS Code extension
# folder that uses it (its package.json finds the grammar one folder up).
install(FILES grammar/sdf.tmLanguage.json DESTINATION ${CMAKE_INSTALL_DATADIR}/sdfc/editors)
install(DIRECTORY grammar/vscode DESTINATION ${CMAKE_INSTALL_DATADIR}/sdfc/editors)
