; indra's Windows installer, made by tools/windows/package with makensis (NSIS 3).
; makensis -DVERSION=0.1.0 -DSOURCE=<the package folder> -DOUTFILE=<setup.exe> indra.nsi
; Installs into Program Files\indra with Start menu shortcuts (started in the install folder, so
; indra finds its scenes and shaders there) and an uninstaller; /S installs silently.
; A 64-bit installer: indra is 64-bit only, and Wine's 64-bit loader (CI) runs no 32-bit stub.
Target amd64-unicode
!include x64.nsh
Name "indra ${VERSION}"
OutFile "${OUTFILE}"
InstallDir "$PROGRAMFILES64\indra"
RequestExecutionLevel admin
; A release is packed with LZMA; CI's test of the installer may ask for zlib (-DCOMPRESSOR=zlib),
; which packs the 110 MB test build in seconds rather than a minute and a half.
!ifndef COMPRESSOR
  !define COMPRESSOR "/SOLID lzma"
!endif
SetCompressor ${COMPRESSOR}
!define UNINSTALL_KEY "Software\Microsoft\Windows\CurrentVersion\Uninstall\indra"

Page directory
Page instfiles
UninstPage uninstConfirm
UninstPage instfiles

Function .onInit
  ${IfNot} ${RunningX64}
    MessageBox MB_ICONSTOP "indra needs 64-bit Windows."
    Abort
  ${EndIf}
  SetRegView 64
FunctionEnd

Section "indra"
  SetOutPath "$INSTDIR"
  File /r "${SOURCE}/*"
  WriteUninstaller "$INSTDIR\uninstall.exe"
  CreateDirectory "$SMPROGRAMS\indra"
  CreateShortcut "$SMPROGRAMS\indra\indra.lnk" "$INSTDIR\indra.exe"
  CreateShortcut "$SMPROGRAMS\indra\indra README.lnk" "$INSTDIR\README.txt"
  CreateShortcut "$SMPROGRAMS\indra\Uninstall indra.lnk" "$INSTDIR\uninstall.exe"
  WriteRegStr HKLM "${UNINSTALL_KEY}" "DisplayName" "indra"
  WriteRegStr HKLM "${UNINSTALL_KEY}" "DisplayVersion" "${VERSION}"
  WriteRegStr HKLM "${UNINSTALL_KEY}" "InstallLocation" "$INSTDIR"
  WriteRegStr HKLM "${UNINSTALL_KEY}" "UninstallString" '"$INSTDIR\uninstall.exe"'
  WriteRegStr HKLM "${UNINSTALL_KEY}" "QuietUninstallString" '"$INSTDIR\uninstall.exe" /S'
SectionEnd

Function un.onInit
  SetRegView 64
FunctionEnd

Section "Uninstall"
  ; Presets and learned mappings live in %APPDATA%\indra and stay.
  RMDir /r "$INSTDIR"
  RMDir /r "$SMPROGRAMS\indra"
  DeleteRegKey HKLM "${UNINSTALL_KEY}"
SectionEnd
