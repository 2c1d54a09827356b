"""toposimp for QGIS: a Processing provider that runs the toposimp executable.

Copy this folder into your QGIS profile's python/plugins (or install the zip from
Plugins > Manage and Install Plugins > Install from ZIP), enable it, and find the algorithms
under "toposimp" in the Processing toolbox. QGIS imports classFactory; the other modules import
QGIS only when the plugin is loaded, so cli_args and runner can be tested without it."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    from .plugin import ToposimpPlugin
    return ToposimpPlugin(iface)
