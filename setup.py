from setuptools import setup

package_name = 'rot_tools'

setup(
    name=package_name,
    version='0.1.0',
    packages=[package_name] + [package_name + '.' + sub
                               for sub in ('core', 'io', 'cli', 'ros', 'ros.client', 'ros.node')],
    data_files=[
        ('share/ament_index/resource_index/packages',
            ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config',
            ['config/rot_tools.yaml', 'config/fastdds_profile.xml']),
        ('share/' + package_name + '/launch', ['launch/rot_tools.launch.xml']),
    ],
    install_requires=['setuptools', 'numpy', 'pyyaml'],
    extras_require={
        'test': ['pytest>=7.4', 'hypothesis>=6.98', 'scipy>=1.11', 'matplotlib>=3.8',
                 'rosbags>=0.11.9,<0.12', 'pyarrow>=25', 'duckdb>=2', 'dask>=2026.8',
                 'distributed>=2026.8', 'evo>=1.38',
                 'opencv-python-headless>=4.10'],
        'plot': ['matplotlib>=3.8'],
        'bag': ['rosbags>=0.11.9,<0.12', 'pyarrow>=25'],
        'fleet': ['dask>=2026.8', 'distributed>=2026.8'],
    },
    zip_safe=True,
    maintainer='rot_tools maintainers',
    maintainer_email='maintainers@rot-tools.example.org',
    description='Rotations, Euler angles, axis-angle and screw motions for ROS 2 and NumPy',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'rotation_node = rot_tools.ros.node.rotation_node:main',
            'rotation_client = rot_tools.ros.client.rotation_client:main',
            'rot-tools = rot_tools.cli.main:main',
        ],
    },
)
